"""pftrack, OpenCV's CSRT and NanoTrack side by side on one video or OTB
folder, each box drawn in its own colour with its confidence, written as a
video; a summary of each tracker's ms per frame (and, with ground truth,
its success AUC) at the end.

    python python/examples/side_by_side.py INPUT BOX|--truth \\
        [--nanotrack DIR] [--frames N] [--out side_by_side.mp4] [--config fast]

INPUT is a video file (anything cv2.VideoCapture opens) or an OTB folder
(img/ with the frames, groundtruth.txt whose first line is the box). BOX is
x,y,w,h in the first frame (taken from groundtruth.txt for an OTB folder).
--nanotrack names the folder with NanoTrack's two ONNX files
(nanotrack_backbone_sim.onnx, nanotrack_head_sim.onnx); without it
NanoTrack is left out. --config fast runs pftrack's Config::fast (the
grey-level correlation filter alone) instead of its default,
Config::accurate. Needs
opencv-contrib-python(-headless) >= 4.7.
"""

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

import pftrack

COLOURS = {"pftrack": (255, 255, 255), "CSRT": (0, 165, 255), "NanoTrack": (255, 0, 255)}


def frames_of(path):
    """The frames of a video file or an OTB folder, as BGR arrays."""
    path = Path(path)
    if path.is_dir():
        for f in sorted((path / "img").iterdir()):
            img = cv2.imread(str(f), cv2.IMREAD_COLOR)
            if img is not None:
                yield img
        return
    video = cv2.VideoCapture(str(path))
    while True:
        ok, frame = video.read()
        if not ok:
            return
        yield frame


def truth_of(path):
    """The OTB ground truth (x, y, w, h per frame), or None."""
    gt = Path(path) / "groundtruth.txt"
    if not gt.exists():
        return None
    rows = []
    for line in gt.read_text().splitlines():
        values = [float(v) for v in line.replace("\t", ",").replace(" ", ",").split(",") if v]
        rows.append(tuple(values[:4]) if len(values) >= 4 else None)
    return rows


def iou(a, b):
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    w = max(0.0, min(ax + aw, bx + bw) - max(ax, bx))
    h = max(0.0, min(ay + ah, by + bh) - max(ay, by))
    union = aw * ah + bw * bh - w * h
    return w * h / union if union > 0 else 0.0


class Pf:
    def __init__(self, config):
        self.name = "pftrack" if config == "default" else f"pftrack ({config})"
        self.t = pftrack.Tracker(seed=1, config=config)

    def init(self, frame, box):
        self.t.init(frame, box)

    def update(self, frame):
        ok, box = self.t.update(frame)
        return box, self.t.estimate.confidence


class OpenCv:
    def __init__(self, name, tracker, score=None):
        self.name, self.t, self.score = name, tracker, score

    def init(self, frame, box):
        self.t.init(frame, tuple(int(round(v)) for v in box))

    def update(self, frame):
        ok, box = self.t.update(frame)
        return (tuple(float(v) for v in box) if ok else None), (self.score() if self.score else float(ok))


def trackers(nanotrack, config):
    out = [Pf(config), OpenCv("CSRT", cv2.TrackerCSRT_create())]
    if nanotrack:
        p = cv2.TrackerNano_Params()
        p.backbone = str(Path(nanotrack) / "nanotrack_backbone_sim.onnx")
        p.neckhead = str(Path(nanotrack) / "nanotrack_head_sim.onnx")
        nano = cv2.TrackerNano_create(p)
        out.append(OpenCv("NanoTrack", nano, nano.getTrackingScore))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("input")
    ap.add_argument("box", nargs="?", help="x,y,w,h (an OTB folder's groundtruth.txt gives it)")
    ap.add_argument("--nanotrack", help="the folder with NanoTrack's two ONNX files")
    ap.add_argument("--frames", type=int, default=0, help="at most this many frames (0: all)")
    ap.add_argument("--out", default="side_by_side.mp4")
    ap.add_argument("--config", default="default", choices=("default", "accurate", "fast"), help="pftrack's configuration")
    a = ap.parse_args()

    truth = truth_of(a.input)
    if a.box:
        box = tuple(float(v) for v in a.box.split(","))
    elif truth and truth[0]:
        box = truth[0]
    else:
        sys.exit("give the first box: x,y,w,h")
    ts = trackers(a.nanotrack, a.config)
    writer, seconds, overlaps = None, {t.name: 0.0 for t in ts}, {t.name: [] for t in ts}
    for n, frame in enumerate(frames_of(a.input)):
        if a.frames and n >= a.frames:
            break
        if writer is None:
            h, w = frame.shape[:2]
            writer = cv2.VideoWriter(a.out, cv2.VideoWriter_fourcc(*"mp4v"), 30, (w, h))
        shown = frame.copy()
        for i, t in enumerate(ts):
            start = time.perf_counter()
            if n == 0:
                t.init(frame, box)
                result, score = box, 1.0
            else:
                result, score = t.update(frame)
            seconds[t.name] += time.perf_counter() - start
            if truth and n < len(truth) and truth[n]:
                overlaps[t.name].append(iou(result, truth[n]) if result else 0.0)
            if result:
                x, y, w, h = (int(round(v)) for v in result)
                cv2.rectangle(shown, (x, y), (x + w, y + h), COLOURS[t.name.split(" ")[0]], 2)
                # Labels stacked above the box, one line a tracker.
                cv2.putText(shown, f"{t.name} {score:.2f}", (x, max(12 * (i + 1), y - 4 - 12 * i)),
                            cv2.FONT_HERSHEY_SIMPLEX, 0.4, COLOURS[t.name.split(" ")[0]], 1)
        writer.write(shown)
    if writer is None:
        sys.exit(f"{a.input}: no frames")
    writer.release()
    frames = n + 1 if not a.frames else min(n + 1, a.frames)
    for t in ts:
        line = f"{t.name}: {1000 * seconds[t.name] / max(frames, 1):.2f} ms a frame"
        if overlaps[t.name]:
            o = np.array(overlaps[t.name])
            auc = np.mean([(o > th).mean() for th in np.linspace(0, 1, 21)])
            line += f", success AUC {auc:.3f} over {len(o)} frames"
        print(line)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
