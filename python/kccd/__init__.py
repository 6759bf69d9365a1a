"""KCCD: strictly conservative continuous collision detection for robots.

Every distance a query reports is a guaranteed lower bound over every configuration in the interval
box it was given. Lengths are metres, angles radians, states in Model.state_names order::

    import kccd
    model = kccd.Model.load("data/demo_arm.yaml")
    checker = kccd.Checker(model)
    r = checker.query(lower, upper, type="distances")
    r.status, r.collision, r.min_distance, r.distance, r.witness_a
"""

from ._kccd import (
    BrakingParams,
    Camera,
    Checker,
    GlContextError,
    InputError,
    Model,
    PoseStatus,
    QueryResult,
    Status,
    TagDetection,
    TagLayout,
    __version__,
    braking_intervals,
    check_log,
    check_overlay_request,
    contact_sheet,
    detect_tags,
    explain,
    fit,
    import_urdf,
    overlay_braking,
    overlay_recording,
    prove_pairs,
    read_bag,
    read_frame,
    read_frames,
    read_image,
    read_lerobot,
    refine_to_edges,
    refine_to_masks,
    render,
    solve_pose,
    synthesize_recording,
    tag_correspondences,
)

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
    "check_log",
    "check_overlay_request",
    "contact_sheet",
    "detect_tags",
    "explain",
    "fit",
    "import_urdf",
    "overlay_braking",
    "overlay_recording",
    "prove_pairs",
    "read_bag",
    "read_frame",
    "read_frames",
    "read_image",
    "read_lerobot",
    "refine_to_edges",
    "refine_to_masks",
    "render",
    "solve_pose",
    "synthesize_recording",
    "tag_correspondences",
]
