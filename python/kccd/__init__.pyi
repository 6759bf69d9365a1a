"""KCCD: strictly conservative continuous collision detection for robots."""

from ._kccd import BrakingParams as BrakingParams
from ._kccd import Camera as Camera
from ._kccd import Checker as Checker
from ._kccd import GlContextError as GlContextError
from ._kccd import InputError as InputError
from ._kccd import Model as Model
from ._kccd import PoseStatus as PoseStatus
from ._kccd import QueryResult as QueryResult
from ._kccd import Status as Status
from ._kccd import TagDetection as TagDetection
from ._kccd import TagLayout as TagLayout
from ._kccd import __version__ as __version__
from ._kccd import braking_intervals as braking_intervals
from ._kccd import contact_sheet as contact_sheet
from ._kccd import detect_tags as detect_tags
from ._kccd import explain as explain
from ._kccd import fit as fit
from ._kccd import import_urdf as import_urdf
from ._kccd import overlay_braking as overlay_braking
from ._kccd import overlay_recording as overlay_recording
from ._kccd import check_log as check_log
from ._kccd import check_overlay_request as check_overlay_request
from ._kccd import prove_pairs as prove_pairs
from ._kccd import read_bag as read_bag
from ._kccd import read_lerobot as read_lerobot
from ._kccd import read_frame as read_frame
from ._kccd import read_frames as read_frames
from ._kccd import read_image as read_image
from ._kccd import refine_to_edges as refine_to_edges
from ._kccd import refine_to_masks as refine_to_masks
from ._kccd import render as render
from ._kccd import solve_pose as solve_pose
from ._kccd import synthesize_recording as synthesize_recording
from ._kccd import tag_correspondences as tag_correspondences

__all__ = [
    "BrakingParams",
    "Camera",
    "Checker",
    "GlContextError",
    "InputError",
    "Model",
    "PoseStatus",
    "QueryResult",
    "Status",
    "TagDetection",
    "TagLayout",
    "__version__",
    "braking_intervals",
    "contact_sheet",
    "detect_tags",
    "explain",
    "fit",
    "import_urdf",
    "overlay_braking",
    "overlay_recording",
    "check_log",
    "check_overlay_request",
    "prove_pairs",
    "read_bag",
    "read_lerobot",
    "read_frame",
    "read_frames",
    "read_image",
    "refine_to_edges",
    "refine_to_masks",
    "render",
    "solve_pose",
    "synthesize_recording",
    "tag_correspondences",
]
