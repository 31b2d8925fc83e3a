"""Throughput of pftrack from Python against the Rust `track run`, on the
same 640x360 I420 frames (the audit scene, `gen-fixtures --throughput`),
already decoded in memory; and two trackers in two threads against one
after the other (`update` releases the GIL).

    python python/benchmarks/throughput.py [TRACK]   (after `tools/run-throughput`,
                                             which makes the clip)
"""

import re
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import pftrack

ROOT = Path(__file__).resolve().parents[2]
TRACK = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "target" / "release" / "track")
CLIP = ROOT / "target" / "throughput" / "throughput_360p_i420.pft"


def frames():
    data = CLIP.read_bytes()
    code, w, h, stride, count = struct.unpack_from("<HHHII", data, 10)
    size = stride * h + 2 * (stride // 2) * (h // 2)
    box = struct.unpack_from("<4f", data, 32)
    return (w, h, stride), box, [data[32 + i * (20 + size) + 20 : 32 + (i + 1) * (20 + size)] for i in range(count)]


def run(shape, box, clip, seed=1):
    raw = ("i420",) + shape
    t = pftrack.Tracker(seed=seed)
    t.init(clip[0], box, raw=raw)
    for f in clip[1:]:
        t.update(f, raw=raw)


def best_of(n, fn):
    times = []
    for _ in range(n):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


shape, box, clip = frames()
python_fps = len(clip) / best_of(5, lambda: run(shape, box, clip))
rust = []
for _ in range(5):
    out = subprocess.run(
        [TRACK, "run", str(CLIP), "--box", ",".join(map(repr, box)), "--summary"],
        capture_output=True, text=True, check=True,
    ).stderr
    rust.append(float(re.search(r"\(([\d.]+) fps\)", out).group(1)))
print(f"Python: {python_fps:.0f} frames/s; Rust track run: {max(rust):.0f} frames/s "
      f"(best of 5 each, {len(clip)} frames of {shape[0]}x{shape[1]} I420)")

alone = best_of(3, lambda: (run(shape, box, clip, 1), run(shape, box, clip, 2)))


def together():
    threads = [threading.Thread(target=run, args=(shape, box, clip, s)) for s in (1, 2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()


both = best_of(3, together)
print(f"two trackers: {alone:.3f} s one after the other, {both:.3f} s in two threads ({alone / both:.2f}x)")
