"""Types of the C++ extension kccd._kccd (re-exported by the kccd package)."""

import enum
import os
from collections.abc import Callable, Sequence
from typing import Any, Literal, TypedDict

import numpy as np
import numpy.typing as npt

__version__: str

_ArrayLike = npt.ArrayLike
_QueryType = Literal["collision", "closest", "nclosest", "distances"]
_Exact = Literal["band", "margin", "all", "off"] | float

class InputError(ValueError):
    """Input that cannot be used; str() is 'source[:line[:column]]: field: problem'."""

    source: str
    line: int
    column: int
    field: str
    problem: str

class GlContextError(RuntimeError):
    """No off-screen GL context (EGL or OSMesa) could be made."""

class Status(enum.IntEnum):
    """A query's outcome; anything but OK means 'unsafe, stop'."""

    OK = 0
    WRONG_STATE_SIZE = 1
    NON_FINITE_STATE = 2
    LOWER_ABOVE_UPPER = 3
    EXACT_NEEDS_POINT = 4
    NUMERICAL_FAILURE = 5

class Model:
    """A robot and its cell; immutable; pickles through its YAML text."""

    @staticmethod
    def load(path: str) -> Model: ...
    @staticmethod
    def from_yaml(text: str, source: str = "<string>") -> Model: ...
    @property
    def name(self) -> str: ...
    @property
    def margin(self) -> float: ...
    @property
    def point_budget(self) -> int: ...
    @property
    def state_size(self) -> int: ...
    @property
    def state_names(self) -> list[str]: ...
    @property
    def joints(self) -> list[str]: ...
    @property
    def bodies(self) -> list[str]: ...
    @property
    def pairs(self) -> list[tuple[str, str]]: ...
    @property
    def yaml(self) -> str: ...
    @property
    def source(self) -> str: ...
    def with_body_geometry(self, body: str, points: _ArrayLike, radius: float) -> Model: ...
    def __getstate__(self) -> tuple[str, str]: ...
    def __setstate__(self, state: tuple[str, str]) -> None: ...

class QueryResult:
    """One query's answer; every distance is a lower bound over the whole box (metres)."""

    @property
    def status(self) -> Status: ...
    @property
    def type(self) -> str: ...
    @property
    def collision(self) -> bool: ...
    @property
    def min_distance(self) -> float: ...
    @property
    def margin(self) -> float: ...
    @property
    def pair(self) -> npt.NDArray[np.int32]: ...
    @property
    def body_a(self) -> npt.NDArray[np.int32]: ...
    @property
    def body_b(self) -> npt.NDArray[np.int32]: ...
    @property
    def distance(self) -> npt.NDArray[np.float64]: ...
    @property
    def witness_a(self) -> npt.NDArray[np.float64]: ...
    @property
    def witness_b(self) -> npt.NDArray[np.float64]: ...
    @property
    def fresh(self) -> npt.NDArray[np.bool_]: ...
    @property
    def has_witness(self) -> npt.NDArray[np.bool_]: ...
    @property
    def stats(self) -> dict[str, Any]: ...
    def __len__(self) -> int: ...

class _ManyResult(TypedDict):
    status: npt.NDArray[np.int8]
    collision: npt.NDArray[np.bool_]
    min_distance: npt.NDArray[np.float64]

class Checker:
    """Answers queries over interval boxes; one Checker per thread."""

    def __init__(self, model: Model, budget_us: float | None = None) -> None: ...
    def query(
        self,
        lower: _ArrayLike,
        upper: _ArrayLike | None = None,
        *,
        type: _QueryType = "collision",
        n: int = 1,
        margin: float | None = None,
        exact: _Exact | None = None,
    ) -> QueryResult: ...
    def query_many(
        self,
        lowers: _ArrayLike,
        uppers: _ArrayLike | None = None,
        *,
        type: _QueryType = "collision",
        n: int = 1,
        margin: float | None = None,
        exact: _Exact | None = None,
        threads: int = 1,
        reuse: bool = False,
    ) -> _ManyResult: ...
    def reset(self) -> None: ...
    @property
    def model(self) -> Model: ...
    @property
    def budget_us(self) -> float | None: ...

class BrakingParams:
    """Braking of one state value (SI units)."""

    position_error: float
    velocity_error: float
    latency: float
    max_acceleration: float
    deceleration: float
    def __init__(
        self,
        *,
        position_error: float = 0.0,
        velocity_error: float = 0.0,
        latency: float = 0.0,
        max_acceleration: float = 0.0,
        deceleration: float = 1.0,
    ) -> None: ...

def overlay_braking() -> BrakingParams: ...

def braking_intervals(
    model: Model, q: _ArrayLike, v: _ArrayLike, params: BrakingParams | Sequence[BrakingParams]
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...

class Camera:
    """A fixed, calibrated camera (intrinsics, distortion, world -> camera pose)."""

    @staticmethod
    def load(path: str, require_pose: bool = True) -> Camera: ...
    def save(self, path: str) -> None: ...
    def with_pose(self, rvec: _ArrayLike, tvec: _ArrayLike) -> Camera: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def camera_matrix(self) -> npt.NDArray[np.float64]: ...
    @property
    def distortion(self) -> list[float]: ...
    @property
    def rvec(self) -> npt.NDArray[np.float64]: ...
    @property
    def tvec(self) -> npt.NDArray[np.float64]: ...
    @property
    def reprojection_rms_px(self) -> float | None: ...
    @property
    def rotation_sigma_deg(self) -> float | None: ...
    @property
    def position_sigma_m(self) -> float | None: ...

class _Rendering(TypedDict):
    rgba: npt.NDArray[np.uint8]
    labels: npt.NDArray[np.uint8] | None
    status: list[str]
    distances: list[float]

def render(
    model: Model,
    camera: Camera,
    *,
    state: _ArrayLike | None = None,
    lower: _ArrayLike | None = None,
    upper: _ArrayLike | None = None,
    mask: bool = False,
    legend: bool = True,
) -> _Rendering: ...
def overlay_recording(
    model: Model,
    camera: Camera,
    video: str = "",
    states: str = "",
    *,
    bag: str = "",
    image_topic: str = "",
    joint_topic: str = "",
    time_source: str = "header",
    joint_map: str = "",
    lerobot: str = "",
    episode: int = -1,
    camera_key: str = "",
    state_key: str = "observation.state",
    frame_by: str = "auto",
    frame_times: str = "",
    ignore_columns: Sequence[str] = (),
    fps: float = 0.0,
    time_offset: float | str = 0.0,
    max_gap: float = 0.0,
    swept: bool = False,
    braking: BrakingParams | None = None,
    plain: bool = False,
    legend: str = "auto",
    visuals: bool = False,
    masks: str = "",
    mask_bodies: Sequence[str] = (),
    frames: str = "",
    jobs: int = 0,
    timings: bool = False,
    output: str = "",
    codec: str = "",
    png_dir: str = "",
    report: str = "",
    contact_sheet: str = "",
    timeline: str = "",
    contact_frames: int = 12,
    progress: Callable[[int, int, float], object] | None = None,
    progress_every: float = 0.0,
) -> dict[str, Any]: ...
def check_overlay_request(
    model: Model | None = None,
    video: str = "",
    states: str = "",
    *,
    bag: str = "",
    image_topic: str = "",
    joint_topic: str = "",
    time_source: str = "header",
    joint_map: str = "",
    lerobot: str = "",
    episode: int = -1,
    camera_key: str = "",
    state_key: str = "observation.state",
    frame_by: str = "auto",
    frame_times: str = "",
    ignore_columns: Sequence[str] = (),
    fps: float = 0.0,
    time_offset: float | str = 0.0,
    max_gap: float = 0.0,
    swept: bool = False,
    braking: BrakingParams | None = None,
    plain: bool = False,
    legend: str = "auto",
    visuals: bool = False,
    masks: str = "",
    mask_bodies: Sequence[str] = (),
    frames: str = "",
    jobs: int = 0,
    timings: bool = False,
    output: str = "",
    codec: str = "",
    png_dir: str = "",
    report: str = "",
    contact_sheet: str = "",
    timeline: str = "",
    contact_frames: int = 12,
) -> None: ...
def read_bag(
    path: str,
    model: Model | None = None,
    *,
    image_topic: str = "",
    joint_topic: str = "",
    time_source: str = "header",
    joint_map: str = "",
    frames: Sequence[int] = (),
) -> dict[str, Any]: ...
def read_lerobot(
    path: str,
    model: Model | None = None,
    *,
    episode: int = -1,
    state_key: str = "observation.state",
    frame_by: str = "auto",
    joint_map: str = "",
) -> dict[str, Any]: ...
def check_log(
    model: Model,
    states: str = "",
    *,
    bag: str = "",
    lerobot: str = "",
    episode: int = -1,
    state_key: str = "observation.state",
    joint_topic: str = "",
    time_source: str = "header",
    joint_map: str = "",
    ignore_columns: Sequence[str] = (),
    rate: float = 0.0,
    max_gap: float = 0.0,
    query: str = "distances",
    swept: bool = False,
    braking: BrakingParams | None = None,
    jobs: int = 0,
    report: str = "",
    timeline: str = "",
) -> dict[str, Any]: ...
def synthesize_recording(
    model: str,
    output: str,
    *,
    camera: str = "",
    seconds: float = 5.0,
    fps: float = 25.0,
    log_rate: float = 125.0,
    time_offset: float = 0.137,
    seed: int = 1,
    codec: str = "ffvhuff",
    collision: bool = True,
    replace: bool = False,
    bag: bool = False,
    width: int | None = None,
    height: int | None = None,
    appearance: str = "auto",
    visible_scale: float | None = None,
    blur: float = 0.7,
    noise: float = 2.5,
    progress: Callable[[float], object] | None = None,
) -> dict[str, Any]: ...

class _Explanation(TypedDict):
    pair: int
    a: str
    b: str
    bound: float
    distance: float
    verdict: Literal["clear", "possible", "real"]
    state: npt.NDArray[np.float64]
    point_a: npt.NDArray[np.float64]
    point_b: npt.NDArray[np.float64]
    evaluations: int

def explain(
    model: Model,
    lower: _ArrayLike,
    upper: _ArrayLike | None = None,
    *,
    margin: float | None = None,
    starts: int = 12,
    max_steps: int = 200,
    seed: int = 1,
) -> list[_Explanation]: ...

class _FitBaselines(TypedDict):
    sphere_volume: float
    sphere_ratio: float | None
    capsule_volume: float
    capsule_ratio: float | None

class _FitPiece(TypedDict, total=False):
    points: npt.NDArray[np.float64]
    radius: float
    volume: float
    hull_volume: float
    volume_ratio: float | None
    baselines: _FitBaselines
    k: int
    hull_vertices: int
    evaluations: int
    outside: float
    tolerance: float
    method: str
    yaml: str
    name: str
    concavity: float

class _Fit(_FitPiece, total=False):
    pieces: list[_FitPiece]
    exact_hull: bool
    triangles: int
    primitives: int

def fit(
    part_path: str,
    points: int = 8,
    *,
    part: str = "",
    merge: bool = False,
    scale: Sequence[float] = (1.0, 1.0, 1.0),
    max_evaluations: int = 4000,
    seed: int = 1,
    exact_hull: bool = False,
    tolerance: float | None = None,
    pieces: int | str = 1,
    concavity: float = 40.0,
    progress: Callable[[float], object] | None = None,
) -> _Fit: ...
def import_urdf(
    urdf_path: str,
    *,
    srdf: str = "",
    points: int | None = None,
    tolerance: float = 2.0,
    pieces: int | str = "auto",
    concavity: float = 40.0,
    safety_margin: float = 0.02,
    packages: dict[str, str] = {},
    visuals: bool = True,
    hulls: bool = False,
    keep_adjacent: bool = False,
    progress: Callable[[float], object] | None = None,
) -> str: ...

_Verdict = Literal["never", "always_touching", "meets", "undecided", "unbounded"]

class _PairProof(TypedDict):
    a: str
    b: str
    frame: str
    verdict: _Verdict
    adjacent: bool
    rigid: bool
    checked: bool
    boxes: int
    ignored: str | None
    ignore_reason: str | None
    bound: float | None
    witness_state: npt.NDArray[np.float64] | None
    witness_distance: float | None
    note: str

class _Proofs(TypedDict):
    margin: float
    pairs: list[_PairProof]
    ignore: list[tuple[str, str, str]]
    dropped: list[tuple[str, str, str]]
    model: Model

def prove_pairs(
    model: Model,
    *,
    margin: float | None = None,
    max_boxes: int = 2000,
    keep_adjacent: bool = False,
    progress: Callable[[float], object] | None = None,
) -> _Proofs: ...
def read_image(path: str) -> npt.NDArray[np.uint8]: ...
def read_frame(video: str, index: int) -> npt.NDArray[np.uint8]: ...
def read_frames(video: str, indices: Sequence[int]) -> list[npt.NDArray[np.uint8]]: ...
def contact_sheet(
    frames: Sequence[npt.NDArray[np.uint8]], captions: Sequence[str], output: str, *, tile_width: int = 320
) -> None: ...

class TagDetection:
    """One detected AprilTag (tag36h11)."""

    @property
    def id(self) -> int: ...
    @property
    def corners(self) -> npt.NDArray[np.float64]: ...
    @property
    def hamming(self) -> int: ...
    @property
    def decision_margin(self) -> float: ...

def detect_tags(image: npt.NDArray[np.uint8]) -> list[TagDetection]: ...

class TagLayout:
    """Where AprilTags are placed in the world."""

    @staticmethod
    def load(path: str) -> TagLayout: ...
    @staticmethod
    def from_yaml(text: str, source: str = "<string>") -> TagLayout: ...
    @property
    def ids(self) -> list[int]: ...
    def corners(self, id: int) -> npt.NDArray[np.float64]: ...
    def __len__(self) -> int: ...

class _Correspondences(TypedDict):
    names: list[str]
    pixels: npt.NDArray[np.float64]
    world: npt.NDArray[np.float64]
    unknown_ids: list[int]

def tag_correspondences(
    detections: Sequence[TagDetection], layout: TagLayout, image: str = "image"
) -> _Correspondences: ...

class PoseStatus(enum.IntEnum):
    """How a pose solve ended; only SOLVED comes with a camera."""

    SOLVED = 0
    TOO_FEW_POINTS = 1
    COLLINEAR = 2
    POOR_GEOMETRY = 3
    TOO_FEW_INLIERS = 4

class _Pose(TypedDict):
    status: PoseStatus
    message: str
    camera: Camera | None
    residuals_px: npt.NDArray[np.float64]
    inlier: npt.NDArray[np.bool_]
    rejected: list[str]
    inliers: int
    covariance: npt.NDArray[np.float64] | None
    reprojection_rms_px: float | None
    rotation_sigma_deg: float | None
    position_sigma_m: float | None

class _MaskFrame(TypedDict):
    iou_before: float
    iou_after: float
    rms_px: float
    outline_points: int

class _Refinement(TypedDict):
    improved: bool
    message: str
    camera: Camera
    frames: list[_MaskFrame]
    iterations: int
    covariance: npt.NDArray[np.float64] | None
    drawn: str

class _EdgeFrame(TypedDict):
    edge_share_before: float
    edge_share_after: float
    rms_px: float
    outline_points: int

class _EdgeRefinement(TypedDict):
    improved: bool
    message: str
    camera: Camera
    frames: list[_EdgeFrame]
    iterations: int
    covariance: npt.NDArray[np.float64] | None
    drawn: str

def refine_to_edges(
    camera: Camera,
    model: Model,
    pictures: Sequence[str | os.PathLike[str] | _ArrayLike],
    states: _ArrayLike,
    *,
    bodies: Sequence[str] | None = None,
    start_is_prior: bool | None = None,
    draw: str = "auto",
) -> _EdgeRefinement: ...

def refine_to_masks(
    camera: Camera,
    model: Model,
    masks: Sequence[str | os.PathLike[str] | _ArrayLike],
    states: _ArrayLike,
    *,
    bodies: Sequence[str] | None = None,
    start_is_prior: bool | None = None,
    draw: str = "auto",
) -> _Refinement: ...
def solve_pose(
    intrinsics: Camera,
    pixels: _ArrayLike,
    world: _ArrayLike,
    names: Sequence[str] | None = None,
    *,
    ransac_threshold_px: float = 8.0,
    min_inliers: int = 6,
) -> _Pose: ...
