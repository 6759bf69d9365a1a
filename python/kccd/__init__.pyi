"""KCCD: strictly conservative continuous collision detection for robots."""

from ._kccd import BrakingParams as BrakingParams
from ._kccd import Camera as Camera
from ._kccd import Checker as Checker
from ._kccd import GlContextError as GlContextError
from ._kccd import InputError as InputError
from ._kccd import Model as Model
from ._kccd import QueryResult as QueryResult
from ._kccd import Status as Status
from ._kccd import __version__ as __version__
from ._kccd import braking_intervals as braking_intervals
from ._kccd import overlay_recording as overlay_recording
from ._kccd import render as render
from ._kccd import synthesize_recording as synthesize_recording

__all__ = [
    "BrakingParams",
    "Camera",
    "Checker",
    "GlContextError",
    "InputError",
    "Model",
    "QueryResult",
    "Status",
    "__version__",
    "braking_intervals",
    "overlay_recording",
    "render",
    "synthesize_recording",
]
