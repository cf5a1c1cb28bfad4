"""Type stubs of the ``symcorr`` extension module (see ``help(symcorr)``)."""

import os
from typing import Dict, Iterable, Iterator, List, Literal, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
JOINT_NAMES: Tuple[str, ...]
"""The 20 Kinect v1 joints, in Kinect SDK v1 order (the row order of a ``(20, 3)`` joints array)."""
SEGMENT_NAMES: Tuple[str, ...]
"""The 17 body segments, in label-index order."""

Vertices = npt.NDArray[np.float64]
Faces = npt.NDArray[np.int64]
JointsLike = Union[Mapping[str, Sequence[float]], npt.ArrayLike]
"""A dict joint name → (x, y, z) with all 20 joints, or a ``(20, 3)`` array in Kinect v1 order."""
Path = Union[str, "os.PathLike[str]"]

class Body:
    """A mesh and its skeleton, checked once; pickles."""

    def __init__(self, vertices: npt.ArrayLike, faces: npt.ArrayLike, joints: JointsLike) -> None: ...
    @property
    def vertices(self) -> Vertices: ...
    @property
    def faces(self) -> Faces: ...
    @property
    def joints(self) -> npt.NDArray[np.float64]:
        """``(20, 3)``, Kinect v1 order."""

BodyLike = Union[Body, Tuple[npt.ArrayLike, npt.ArrayLike, JointsLike]]

class Correspondence:
    """A correspondence; pickles."""

    pairs: npt.NDArray[np.int64]
    """``(k, 2)``: template vertex, target vertex (the ids of the inputs)."""
    confidence: npt.NDArray[np.float64]
    """``(k,)``."""
    no_counterpart: Optional[npt.NDArray[np.int64]]
    """Template vertices a partial target (a single-view scan) does not show; ``None`` for a whole target."""
    timings: Dict[str, float]
    """Seconds per stage, and ``total``."""
    method: str
    coverage: Optional[float]
    """Fraction of target vertices hit (``None`` for the paper's method)."""
    surface_corners: Optional[npt.NDArray[np.int64]]
    """``(k, 3)``: per pair the corners (target ids) of the target triangle its template point reaches; the articulated method only."""
    surface_weights: Optional[npt.NDArray[np.float64]]
    """``(k, 3)``: the barycentric weights of that point on the triangle."""
    view_held: Optional[float]
    """A single-view target (articulated method): the fraction of the template points the fit shows the camera that lie on the scan; ``None`` elsewhere."""
    turned_about_spine: bool
    """The target's joints faced away from the camera and were turned half a turn about their spine before the match."""
    def __init__(
        self,
        pairs: npt.NDArray[np.int64],
        confidence: npt.NDArray[np.float64],
        no_counterpart: Optional[npt.NDArray[np.int64]],
        timings: Dict[str, float],
        method: str,
        coverage: Optional[float],
        surface_corners: Optional[npt.NDArray[np.int64]] = None,
        surface_weights: Optional[npt.NDArray[np.float64]] = None,
        view_held: Optional[float] = None,
        turned_about_spine: bool = False,
    ) -> None: ...
    def __len__(self) -> int: ...

class Labels:
    """Segment labels of a mesh; pickles."""

    segments: npt.NDArray[np.int64]
    """``(n,)``: index into ``names``; −1 for a vertex in a component no bone reaches."""
    names: List[str]
    joints: Dict[str, Tuple[float, float, float]]
    """The joints as the attachment refined them."""
    fit_score: float
    corrections: Dict[str, object]
    """``turned_triangles``, ``mirrored_fixed``, ``limbs_swapped`` (``"arms"``, ``"legs"`` or ``None``: that limb pair's sides swapped back alone), ``joint_moves``, ``repaired_joints``, ``accepted_poor_fit``, ``unreached_vertices``."""
    def __init__(
        self,
        segments: npt.NDArray[np.int64],
        names: List[str],
        joints: Dict[str, Tuple[float, float, float]],
        fit_score: float,
        corrections: Dict[str, object],
    ) -> None: ...

class Prepared:
    """A template prepared once, matched against many targets."""

    def __init__(
        self,
        template: BodyLike,
        method: str = "articulated",
        dense: bool = True,
        *,
        samples: int = 1000,
        accept_poor_fit: bool = False,
    ) -> None: ...
    def match(self, target: BodyLike) -> Correspondence: ...
    @property
    def method(self) -> str: ...
    @property
    def template(self) -> Body: ...
    @property
    def segments(self) -> npt.NDArray[np.int64]: ...

class Frame:
    """One frame of :func:`track`; pickles. Array fields are ``None`` for a skipped frame."""

    index: int
    time_s: float
    status: str
    """``"ok"`` or ``"skipped"``."""
    reason: Optional[str]
    target_of: Optional[npt.NDArray[np.int32]]
    """``(n,)``: per template vertex the scan vertex it matches, −1 where the frame does not show it."""
    confidence: Optional[npt.NDArray[np.float32]]
    posed: Optional[npt.NDArray[np.float32]]
    """``(n, 3)``: the template posed onto the frame, camera space, metres."""
    scan: Optional[Tuple[Vertices, Faces]]
    corrections: Optional[List[str]]
    coverage: Optional[float]
    mean_confidence: Optional[float]
    fit_score: Optional[float]
    warm: Optional[bool]
    timings: Optional[Dict[str, float]]
    view_held: Optional[float]
    """The fraction of the template points the fit shows the camera that lie on the scan."""

class FrameIterator(Iterator[Frame]):
    def __iter__(self) -> "FrameIterator": ...
    def __next__(self) -> Frame: ...
    def __len__(self) -> int: ...

def read_mesh(path: Path) -> Tuple[Vertices, Faces]:
    """Reads OBJ/OFF/PLY/glTF/GLB in the file's vertex order. ``OSError`` / ``ValueError``."""

def read_joints(path: Path, frame: Optional[int] = None) -> Dict[str, Tuple[float, float, float]]:
    """One frame of a joint file (any format symcorr reads) as the 20 Kinect v1 joints."""

def read_depth(path: Path) -> npt.NDArray[np.uint16]:
    """A 16-bit PNG depth image (mm) as ``(h, w)``."""

def label(
    vertices: npt.ArrayLike,
    faces: npt.ArrayLike,
    joints: JointsLike,
    *,
    boundaries: str = "joint-planes",
    accept_poor_fit: bool = False,
) -> Labels:
    """Segment label per vertex, as ``symcorr label``."""

def match(
    template: BodyLike,
    target: BodyLike,
    method: str = "articulated",
    dense: bool = True,
    *,
    samples: int = 1000,
    accept_poor_fit: bool = False,
) -> Correspondence:
    """Template → target correspondence, as ``symcorr match`` (same pairs)."""

def scan(
    depth: npt.NDArray[np.uint16],
    intrinsics: Union[Mapping[str, Union[float, bool, Sequence[float]]], Path],
    joints: JointsLike,
    *,
    discontinuity: float = 0.05,
    keep_floor: bool = False,
) -> Tuple[Vertices, Faces, npt.NDArray[np.int64]]:
    """Depth image (mm) → scan mesh (camera space, metres) and per-vertex pixel ids."""

def track(
    recording: Path,
    joints: Path,
    template: Union[BodyLike, Prepared],
    *,
    frames: Optional[Iterable[int]] = None,
    joint_offset: Union[float, Literal["auto"], None] = None,
    check_log: bool = True,
    intrinsics: Union[Mapping[str, Union[float, bool, Sequence[float]]], Path, None] = None,
) -> FrameIterator:
    """The frames of a recording matched one by one, as ``symcorr track``: the joint log read
    at each frame's time + ``joint_offset`` seconds (``None``: 0; ``"auto"``: estimated from the
    frames), refused first when it does not fit the frames (``check_log``); ``intrinsics``
    replaces the recording's."""
