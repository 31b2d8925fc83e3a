"""pftrack: a colour particle-filter object tracker, with OpenCV's tracker
interface.

    import pftrack
    t = pftrack.Tracker(seed=1)          # settings as keywords, e.g. lost_below=0.6
                                         # particles=25, 50, 100 (the default), 200 or 400
    t.init(frame, (x, y, w, h))          # an HxWx3 BGR (or rgb=True) or HxW uint8 array
    ok, box = t.update(next_frame)       # ok while tracking
    t.estimate.confidence                # and .state, .event, .bbox, .ellipse

Raw camera frames: ``t.update(data, raw=("rgb565", width, height, stride))``.
The same seed and frames give the same track, bit for bit, as the Rust
library and the ``track`` tool.
"""

from ._pftrack import Estimate, Tracker

__all__ = ["Tracker", "Estimate"]
