"""Parallax: incremental Structure from Motion, from Python.

The pipeline, one call per step (keyword options are the command line's flags, '_' for '-'):

    import parallax
    parallax.extract_features("photos/", "run/database.db")
    parallax.match("run/database.db", pairs="exhaustive")
    models = parallax.map("run/database.db", "photos/", "run/")
    # or all at once:
    result = parallax.reconstruct("photos/", "run/", intrinsics="K.txt")
    model = result.models[0]
    model.projection_centers()        # N x 3, no Python loop
    model.point3D_xyz()               # M x 3

Everything runs in Parallax's C++ core (the extension module parallax._parallax); long calls
release the GIL, report progress through `progress=callable(stage, done, total)` and stop
cleanly on Ctrl-C. Bad input raises ValueError, a missing file FileNotFoundError, each with
the command line's one-line message.
"""

from ._parallax import (  # noqa: F401
    Camera,
    CameraMap,
    EstimationResult,
    ExtractionResult,
    Image,
    ImageMap,
    MatchResult,
    Point3D,
    Point3DMap,
    Reconstruction,
    ReconstructionResult,
    Rigid3d,
    Track,
    TrackElement,
    calibrate,
    dlt_resection,
    estimate_absolute_pose,
    estimate_essential_matrix,
    estimate_fundamental_matrix,
    estimate_homography,
    evaluate,
    export_model,
    extract_features,
    extract_sift,
    read_image,
    map,
    match,
    reconstruct,
    set_log_level,
    synthesize,
    triangulate_points,
    undistort,
    write_report,
)

# pycolmap's names and habits (docs/colmap-dropin.md): `import parallax as pycolmap`.
from ._pycolmap import (  # noqa: F401,E402
    Database,
    Rotation3d,
    absolute_pose_estimation,
    essential_matrix_estimation,
    estimate_absolute_pose,
    estimate_essential_matrix,
    estimate_fundamental_matrix,
    estimate_homography_matrix,
    extract_features,
    fundamental_matrix_estimation,
    homography_matrix_estimation,
    incremental_mapping,
    match_exhaustive,
    match_sequential,
    match_spatial,
    match_vocabtree,
    triangulate_points,
    undistort_images,
)

__version__ = "0.1.0"


class _ReadOnClassOrModel:
    """Reconstruction.read(path) returns a new model (Parallax's way); model.read(path) reads
    into that model, as pycolmap's does, instead of returning a new one and leaving it empty."""

    def __get__(self, model, cls):
        if model is None:
            return cls
        return model._read_into


Reconstruction.read = _ReadOnClassOrModel()


def read_model(path):
    """Reads a COLMAP model folder (cameras/images/points3D, .bin or .txt)."""
    return Reconstruction.read(path)
