#!/usr/bin/env python3
"""Runs OpenCV's trackers on OTB sequences and writes their tracks in the
format `track score` reads: <out>/<tracker>/<sequence>.txt (x,y,w,h per frame,
the first being the initial box), <sequence>.ms (median ms per update) and,
for a tracker with a confidence of its own, <sequence>.confidence (one per
update, as `track otb` writes pftrack's).

Trackers: CSRT, KCF, MIL, MOSSE (opencv-contrib's legacy API), the classic
meanShift / CamShift on a hue back-projection (the OpenCV tutorial's recipe:
hue histogram of the initial box, masked to saturated, not-too-dark pixels),
and with --nanotrack NanoTrack (cv2.TrackerNano, a Siamese network; its
confidence is getTrackingScore()). A tracker that reports failure keeps its
last box, so every frame has one, as OTB's one-pass evaluation expects.

Usage: opencv_trackers.py --out DIR [--only NAMES] [--perturb DX,DY,SCALE]
                          [--nanotrack MODEL_DIR] SEQ_DIR...

--nanotrack names the folder with NanoTrack's nanotrack_backbone_sim.onnx
and nanotrack_head_sim.onnx; without it NanoTrack is not run.

--perturb starts every tracker from the first box moved by DX of its width
and DY of its height and scaled by SCALE about its centre, as `track otb
--perturb` does (OTB's spatial robustness evaluation).
"""
import argparse
import pathlib
import statistics
import sys
import time

import cv2
import numpy as np


def load_truth(seq):
    rows = []
    for line in (seq / "groundtruth.txt").read_text().splitlines():
        line = line.strip()
        if not line:
            continue
        parts = [p for p in line.replace("\t", ",").replace(" ", ",").split(",") if p]
        rows.append(tuple(float(v) for v in parts[:4]))
    return rows


def perturbed(box, dx, dy, scale):
    """The first box changed as `track --perturb` changes it (host-tests otb::Perturb)."""
    x, y, w, h = box
    cx, cy = x + w * (0.5 + dx), y + h * (0.5 + dy)
    w, h = w * scale, h * scale
    return (cx - w / 2, cy - h / 2, w, h)


def frames(seq):
    exts = {".jpg", ".jpeg", ".png", ".bmp"}
    return sorted(p for p in (seq / "img").iterdir() if p.suffix.lower() in exts)


class Legacy:
    """An opencv-contrib tracker through the legacy API (the only one with MOSSE)."""

    def __init__(self, name):
        self.make = getattr(cv2.legacy, f"Tracker{name}_create")

    def init(self, img, box):
        self.failures = 0
        self.t = self.make()
        self.t.init(img, tuple(int(round(v)) for v in box))
        self.box = box

    def update(self, img):
        ok, box = self.t.update(img)
        if ok:
            self.box = tuple(float(v) for v in box)
        else:
            self.failures += 1
        return self.box


class HueShift:
    """meanShift or CamShift on the back-projection of the initial hue histogram."""

    def __init__(self, cam):
        self.cam = cam
        self.crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 1)

    def init(self, img, box):
        x, y, w, h = (int(round(v)) for v in box)
        # A perturbed start may reach past the frame: take the part inside.
        x0, y0 = max(x, 0), max(y, 0)
        w, h = min(x + w, img.shape[1]) - x0, min(y + h, img.shape[0]) - y0
        x, y = x0, y0
        if w <= 0 or h <= 0:
            raise ValueError("the first box is outside the frame")
        hsv = cv2.cvtColor(img[y:y + h, x:x + w], cv2.COLOR_BGR2HSV)
        mask = cv2.inRange(hsv, np.array((0.0, 60.0, 32.0)), np.array((180.0, 255.0, 255.0)))
        self.hist = cv2.calcHist([hsv], [0], mask, [180], [0, 180])
        cv2.normalize(self.hist, self.hist, 0, 255, cv2.NORM_MINMAX)
        self.win = (x, y, max(w, 1), max(h, 1))
        self.box = box

    def update(self, img):
        hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV)
        back = cv2.calcBackProject([hsv], [0], self.hist, [0, 180], 1)
        if self.cam:
            rot, win = cv2.CamShift(back, self.win, self.crit)
            if win[2] > 0 and win[3] > 0:
                self.win = win
                x, y, w, h = cv2.boundingRect(cv2.boxPoints(rot).astype(np.float32))
                self.box = (float(x), float(y), float(w), float(h))
        else:
            _, win = cv2.meanShift(back, self.win, self.crit)
            self.win = win
            self.box = tuple(float(v) for v in win)
        return self.box


class Nano(Legacy):
    """NanoTrack (OpenCV's TrackerNano) with its two ONNX files from `models`,
    driven as the legacy trackers are, keeping its score after each update."""

    FILES = ("nanotrack_backbone_sim.onnx", "nanotrack_head_sim.onnx")

    def __init__(self, models):
        params = cv2.TrackerNano_Params()
        params.backbone, params.neckhead = (str(models / f) for f in self.FILES)
        self.make = lambda: cv2.TrackerNano.create(params)

    def init(self, img, box):
        super().init(img, box)
        self.scores = []

    def update(self, img):
        box = super().update(img)
        # Read after the update: the score of the box it just chose.
        self.scores.append(float(self.t.getTrackingScore()))
        return box


TRACKERS = {
    "CSRT": lambda: Legacy("CSRT"),
    "KCF": lambda: Legacy("KCF"),
    "MIL": lambda: Legacy("MIL"),
    "MOSSE": lambda: Legacy("MOSSE"),
    "meanShift": lambda: HueShift(cam=False),
    "CamShift": lambda: HueShift(cam=True),
    "NanoTrack": None,  # needs --nanotrack; made in main()
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True, type=pathlib.Path)
    ap.add_argument("--only", help="comma-separated tracker names")
    ap.add_argument("--perturb", metavar="DX,DY,SCALE", help="change the first box (see above)")
    ap.add_argument("--nanotrack", type=pathlib.Path, metavar="MODEL_DIR", help="NanoTrack's ONNX files")
    ap.add_argument("seqs", nargs="+", type=pathlib.Path)
    args = ap.parse_args()
    makers = dict(TRACKERS)
    if args.nanotrack:
        missing = [f for f in Nano.FILES if not (args.nanotrack / f).is_file()]
        if missing:
            sys.exit(f"error: --nanotrack {args.nanotrack}: no {', '.join(missing)}")
        makers["NanoTrack"] = lambda: Nano(args.nanotrack)
    change = (0.0, 0.0, 1.0)
    if args.perturb:
        try:
            change = tuple(float(v) for v in args.perturb.split(","))
        except ValueError:
            change = ()
        if len(change) != 3 or not all(np.isfinite(change)) or change[2] <= 0:
            sys.exit(f"error: --perturb `{args.perturb}` is not three numbers DX,DY,SCALE with SCALE above 0")
    names = args.only.split(",") if args.only else [n for n, make in makers.items() if make]
    unknown = [n for n in names if n not in TRACKERS]
    if unknown:
        sys.exit(f"error: unknown tracker(s) {', '.join(unknown)}; known: {', '.join(TRACKERS)}")
    if "NanoTrack" in names and not makers["NanoTrack"]:
        sys.exit("error: NanoTrack needs --nanotrack MODEL_DIR")
    cv2.setNumThreads(1)  # per-frame times comparable with the single-threaded core
    for seq in args.seqs:
        # Bad input is a one-line error naming the sequence, not a traceback.
        try:
            truth = load_truth(seq)
            paths = frames(seq)
        except (OSError, ValueError) as e:
            sys.exit(f"error: {seq}: {e}")
        if not truth or len(paths) != len(truth):
            sys.exit(f"error: {seq}: {len(paths)} images but {len(truth)} boxes")
        images = [cv2.imread(str(p), cv2.IMREAD_COLOR) for p in paths]
        if any(img is None for img in images):
            sys.exit(f"error: {seq}: an image could not be decoded")
        start = perturbed(truth[0], *change)
        for name in names:
            tracker = makers[name]()
            try:
                tracker.init(images[0], start)
            except (ValueError, cv2.error) as e:
                sys.exit(f"error: {seq}: {name} cannot start from {start}: {e}")
            boxes, times = [start], []
            for img in images[1:]:
                t0 = time.perf_counter()
                box = tracker.update(img)
                times.append((time.perf_counter() - t0) * 1e3)
                boxes.append(box)
            out = args.out / f"opencv-{name}"
            out.mkdir(parents=True, exist_ok=True)
            (out / f"{seq.name}.txt").write_text("".join(f"{x:.2f},{y:.2f},{w:.2f},{h:.2f}\n" for x, y, w, h in boxes))
            (out / f"{seq.name}.ms").write_text(f"{statistics.median(times):.4f}\n")
            if hasattr(tracker, "scores"):
                (out / f"{seq.name}.confidence").write_text("".join(f"{s!r}\n" for s in tracker.scores))
            failed = getattr(tracker, "failures", 0)
            print(
                f"{seq.name:>10} {name:>9}: {statistics.median(times):8.3f} ms/frame, "
                f"update reported failure on {failed} of {len(images) - 1} frames",
                flush=True,
            )


if __name__ == "__main__":
    main()
