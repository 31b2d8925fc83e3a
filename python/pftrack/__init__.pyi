from typing import Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

Box = Tuple[float, float, float, float]
Raw = Tuple[str, int, int, int]
FrameLike = Union[npt.NDArray[np.uint8], bytes, bytearray]

class Estimate:
    """What the last ``init`` or ``update`` found."""

    bbox: Box
    """The box, ``(x, y, w, h)`` in pixels."""
    confidence: float
    """The probability that the estimate is on the target, in ``[0, 1]``."""
    state: str
    """``"searching"``, ``"tracking"`` or ``"lost"``."""
    event: Optional[str]
    """``None``, ``"initialised"``, ``"acquired"``, ``"lost"`` or ``"reacquired"``."""
    ellipse: Box
    """The ellipse, ``(cx, cy, half_width, half_height)``."""

class Tracker:
    """A colour particle-filter tracker with OpenCV's interface.

    ``particles`` is 25, 50, 100, 200 or 400 (fewer run faster; any other
    count raises ``ValueError``); ``seed`` makes runs repeatable; ``rgb``
    reads HxWx3 arrays as RGB instead of OpenCV's BGR. Settings: ``config``
    (``"default"``, which is ``"accurate"``: both correlation filters and a
    lost target looked for where it was lost; or ``"fast"``: the grey-level
    filter alone, a lost target looked for over the frame, less accurate and
    taking about a fifth less time a frame; the other settings apply over it), ``lost_below``, ``found_above``, ``alpha``, ``sure_share`` (floats),
    ``lost_after`` (int), ``correlation``, ``scene_motion`` (bools),
    ``redetect`` (``"off"``, ``"near"``, the default, or ``"frame"``). Bad
    settings raise ``ValueError`` (out of range) or ``TypeError`` (unknown).
    """

    def __init__(
        self,
        particles: int = 100,
        seed: int = 1,
        rgb: bool = False,
        *,
        config: str = ...,
        lost_below: float = ...,
        found_above: float = ...,
        alpha: float = ...,
        lost_after: int = ...,
        correlation: bool = ...,
        scene_motion: bool = ...,
        redetect: str = ...,
        sure_share: float = ...,
    ) -> None: ...
    def init(self, frame: FrameLike, box_: Box, raw: Optional[Raw] = None) -> bool:
        """Learns the target in ``box_`` and tracks it from there (again to re-initialise).

        Raises ``ValueError`` for a bad box or frame, ``TypeError`` for a wrong dtype or shape.
        """
    def update(self, frame: FrameLike, raw: Optional[Raw] = None) -> Tuple[bool, Box]:
        """Tracks one frame: ``(ok, box)``, ``ok`` while tracking. Releases the GIL while it runs."""
    @property
    def particles(self) -> int:
        """The number of particles."""
    @property
    def estimate(self) -> Optional[Estimate]:
        """The last estimate (``None`` before ``init``)."""
