"""pycolmap's names and habits beside Parallax's own, so that `import parallax as pycolmap` runs
the common notebook code unchanged (docs/colmap-dropin.md lists what works and what does not).

Each alias calls the Parallax function that does the same work; none has a second
implementation. Where pycolmap and Parallax share a name with other arguments
(extract_features, the estimators) one function takes both.
"""

import os
import shutil
import sqlite3
import tempfile

import numpy as np

from . import _parallax

_COLMAP_MODEL_FILES = ("cameras", "images", "points3D", "rigs", "frames")


# ----- Geometry ---------------------------------------------------------------------------------


class Rotation3d(np.ndarray):
    """A rotation matrix (3 x 3 array) that also answers pycolmap's Rotation3d calls:
    `.matrix()`, `.quat` (x, y, z, w, pycolmap's order), `.inverse()`. Built from a 3 x 3
    matrix, from a quaternion in pycolmap's x, y, z, w order, or empty (identity)."""

    def __new__(cls, value=None):
        if value is None:
            matrix = np.eye(3)
        else:
            array = np.asarray(value, dtype=float)
            if array.shape == (4,):
                matrix = _matrix_from_xyzw(array)
            elif array.shape == (3, 3):
                matrix = array
            else:
                raise ValueError("Rotation3d takes a 3 x 3 matrix or a quaternion (x, y, z, w), "
                                 f"not an array of shape {array.shape}")
        return np.array(matrix, dtype=float).view(cls)

    def matrix(self):
        return np.array(self)

    @property
    def quat(self):
        return _xyzw_from_matrix(np.array(self))

    def inverse(self):
        return Rotation3d(np.array(self).T)

    def __mul__(self, other):
        # pycolmap: rotation * rotation composes, rotation * points rotates.
        other_array = np.asarray(other, dtype=float)
        if other_array.shape == (3, 3):
            return Rotation3d(np.array(self) @ other_array)
        if other_array.ndim == 2 and other_array.shape[1] == 3:
            return other_array @ np.array(self).T
        return np.array(self) @ other_array


def _matrix_from_xyzw(quat):
    x, y, z, w = quat / np.linalg.norm(quat)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _xyzw_from_matrix(matrix):
    # Shepperd's method: the largest of the four squared components first, for stability.
    trace = np.trace(matrix)
    candidates = [trace, matrix[0, 0], matrix[1, 1], matrix[2, 2]]
    largest = int(np.argmax(candidates))
    if largest == 0:
        w = 0.5 * np.sqrt(1 + trace)
        x = (matrix[2, 1] - matrix[1, 2]) / (4 * w)
        y = (matrix[0, 2] - matrix[2, 0]) / (4 * w)
        z = (matrix[1, 0] - matrix[0, 1]) / (4 * w)
    else:
        i = largest - 1
        j, k = (i + 1) % 3, (i + 2) % 3
        v = np.zeros(3)
        v[i] = 0.5 * np.sqrt(1 + matrix[i, i] - matrix[j, j] - matrix[k, k])
        v[j] = (matrix[j, i] + matrix[i, j]) / (4 * v[i])
        v[k] = (matrix[k, i] + matrix[i, k]) / (4 * v[i])
        w = (matrix[k, j] - matrix[j, k]) / (4 * v[i])
        x, y, z = v
    quat = np.array([x, y, z, w])
    return quat if w >= 0 else -quat


def _patch_rigid3d():
    rotation = _parallax.Rigid3d.rotation
    _parallax.Rigid3d.rotation = property(
        lambda self: Rotation3d(rotation.fget(self)),
        lambda self, value: rotation.fset(self, np.asarray(value, dtype=float)),
        doc="The rotation: a 3 x 3 matrix with pycolmap's Rotation3d calls (.matrix(), .quat).")
    # pycolmap 3.12 made Image.cam_from_world a method: `image.cam_from_world()` and
    # `image.cam_from_world.rotation` both work.
    _parallax.Rigid3d.__call__ = lambda self: self


# ----- Reconstruction ---------------------------------------------------------------------------


def _patch_reconstruction():
    reconstruction = _parallax.Reconstruction
    reconstruction.export_PLY = reconstruction.export_ply  # pycolmap's spelling.
    _parallax.Camera.calibration_matrix = lambda camera: camera.K


# ----- Estimators -------------------------------------------------------------------------------

# The key pycolmap's estimators return their model under, by Parallax function.
_MODEL_KEYS = ("E", "F", "H", "cam_from_world")


def _result_getitem(result, key):
    """pycolmap's estimators return dicts: result["E"], result["num_inliers"], ..."""
    if key in _MODEL_KEYS:
        return result.model
    if key in ("num_inliers", "inlier_mask", "cam2_from_cam1"):
        return getattr(result, key)
    raise KeyError(key)


def _patch_estimation_result():
    _parallax.EstimationResult.__getitem__ = _result_getitem
    _parallax.EstimationResult.keys = lambda result: [
        key for key in ("num_inliers", "inlier_mask", "cam2_from_cam1")
        if key != "cam2_from_cam1" or result.cam2_from_cam1 is not None]


def _ransac_kwargs(estimation_options, kwargs):
    """pycolmap's estimation_options={"ransac": {"max_error": ...}} or an options object with
    .ransac.max_error, as Parallax's keyword options."""
    if estimation_options is None:
        return kwargs
    ransac = estimation_options.get("ransac", estimation_options) if isinstance(
        estimation_options, dict) else getattr(estimation_options, "ransac", estimation_options)
    for name in ("max_error", "confidence", "max_num_trials"):
        value = ransac.get(name) if isinstance(ransac, dict) else getattr(ransac, name, None)
        if value is not None:
            kwargs.setdefault(name, value)
    return kwargs


def estimate_essential_matrix(points1, points2, K1, K2=None, estimation_options=None, **kwargs):
    """Parallax's (points, K1, K2) or pycolmap's (points2D1, points2D2, camera1, camera2,
    estimation_options). With cameras, the points are undistorted by each camera's model and the
    threshold, given in pixels, is divided by the mean focal length."""
    kwargs = _ransac_kwargs(estimation_options, kwargs)
    if isinstance(K1, _parallax.Camera):
        camera1, camera2 = K1, K2 if K2 is not None else K1
        normalized1 = camera1.cam_from_img(np.asarray(points1, dtype=float))
        normalized2 = camera2.cam_from_img(np.asarray(points2, dtype=float))
        focal = 0.5 * (camera1.focal_length + camera2.focal_length)
        if "max_error" in kwargs:
            kwargs["max_error"] = kwargs["max_error"] / focal
        else:
            kwargs["max_error"] = 4.0 / focal  # pycolmap's default threshold, 4 px.
        return _parallax.estimate_essential_matrix(normalized1, normalized2, np.eye(3), np.eye(3),
                                                   **kwargs)
    return _parallax.estimate_essential_matrix(points1, points2, K1, K2, **kwargs)


def estimate_fundamental_matrix(points1, points2, estimation_options=None, **kwargs):
    return _parallax.estimate_fundamental_matrix(points1, points2,
                                                 **_ransac_kwargs(estimation_options, kwargs))


def estimate_homography_matrix(points1, points2, estimation_options=None, **kwargs):
    """pycolmap's name for estimate_homography."""
    return _parallax.estimate_homography(points1, points2,
                                         **_ransac_kwargs(estimation_options, kwargs))


def estimate_absolute_pose(points2D, points3D, camera, estimation_options=None, **kwargs):
    return _parallax.estimate_absolute_pose(points2D, points3D, camera,
                                            **_ransac_kwargs(estimation_options, kwargs))


# ----- Pipeline ---------------------------------------------------------------------------------


def extract_features(*args, **kwargs):
    """Parallax's extract_features(image_dir, database) or pycolmap's
    extract_features(database_path, image_path, camera_model=...): told apart by the keywords,
    or else by which argument is the folder of images."""
    pycolmap_names = {"database_path", "image_path", "camera_mode", "reader_options",
                      "sift_options", "extraction_options", "device", "image_list",
                      "image_names"}
    if args and len(args) >= 2 and not pycolmap_names & kwargs.keys():
        first, second = os.fspath(args[0]), os.fspath(args[1])
        if os.path.isdir(first) or not os.path.isdir(second):
            return _parallax.extract_features(*args, **kwargs)
    names = ["database_path", "image_path"]
    for name, value in zip(names, args):
        kwargs[name] = value
    database_path = kwargs.pop("database_path")
    image_path = kwargs.pop("image_path")
    options = {}
    camera_mode = kwargs.pop("camera_mode", None)
    mode = str(getattr(camera_mode, "name", camera_mode) or "AUTO").upper()
    if mode.endswith("SINGLE"):
        options["single_camera"] = True
    elif mode.endswith("PER_IMAGE"):
        options["camera_per_image"] = True
    if "camera_model" in kwargs:
        options["camera_model"] = kwargs.pop("camera_model")
    reader = kwargs.pop("reader_options", None) or {}
    if isinstance(reader, dict) and reader.get("camera_model"):
        options["camera_model"] = reader["camera_model"]
    for ignored in ("sift_options", "extraction_options", "device", "image_list", "image_names",
                    "verbose"):
        kwargs.pop(ignored, None)
    options.update(kwargs)
    return _parallax.extract_features(image_path, database_path, **options)


def _match(pairs, database_path, options):
    for ignored in ("sift_options", "matching_options", "verification_options", "device",
                    "pairing_options", "verbose"):
        options.pop(ignored, None)
    return _parallax.match(database_path, pairs=pairs, **options)


def match_exhaustive(database_path, **options):
    return _match("exhaustive", database_path, options)


def match_sequential(database_path, **options):
    return _match("sequential", database_path, options)


def match_spatial(database_path, **options):
    return _match("spatial", database_path, options)


def match_vocabtree(database_path, **options):
    return _match("retrieval", database_path, options)


def incremental_mapping(database_path, image_path, output_path, options=None, input_path=None,
                        **kwargs):
    """pycolmap's: maps the database and writes each model into <output_path>/<k>/ (binary, as
    COLMAP does); returns {k: Reconstruction}. `options` (a dict of Parallax's mapper keywords)
    and keywords go to parallax.map."""
    parallax_options = dict(options) if isinstance(options, dict) else {}
    parallax_options.update(kwargs)
    if input_path is not None:
        parallax_options["input_model"] = os.fspath(input_path)
    output_path = os.fspath(output_path)
    os.makedirs(output_path, exist_ok=True)
    staging = tempfile.mkdtemp(prefix=".parallax-", dir=output_path)
    try:
        models = _parallax.map(database_path, image_path, staging, no_text=True,
                               **parallax_options)
        result = {}
        for index, model in enumerate(models):
            target = os.path.join(output_path, str(index))
            shutil.rmtree(target, ignore_errors=True)
            shutil.move(os.path.join(staging, "sparse", str(index)), target)
            result[index] = model
        return result
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def undistort_images(output_path, input_path, image_path, **options):
    """pycolmap's argument order: the workspace to write, the model, the images."""
    return _parallax.undistort(input_path, image_path, output_path, **options)


# pycolmap 0.x's names of the estimators.
absolute_pose_estimation = estimate_absolute_pose
essential_matrix_estimation = estimate_essential_matrix
fundamental_matrix_estimation = estimate_fundamental_matrix
homography_matrix_estimation = estimate_homography_matrix


def triangulate_points(*args, **kwargs):
    """Parallax's triangulate_points(P1, P2, points1, points2) (the DLT of matched points), or
    pycolmap's triangulate_points(reconstruction, database_path, image_path, output_path): the
    database's points triangulated into the reconstruction's poses, which stay as given (COLMAP's
    point_triangulator; `parallax mapper --fixed-poses`). The model is written into output_path
    and returned."""
    first = args[0] if args else kwargs.get("reconstruction")
    if not isinstance(first, _parallax.Reconstruction):
        return _parallax.triangulate_points(*args, **kwargs)
    names = ["reconstruction", "database_path", "image_path", "output_path"]
    for name, value in zip(names, args):
        kwargs[name] = value
    reconstruction = kwargs.pop("reconstruction")
    database_path = kwargs.pop("database_path")
    image_path = kwargs.pop("image_path")
    output_path = os.fspath(kwargs.pop("output_path"))
    for ignored in ("clear_points", "options", "refine_intrinsics", "verbose"):
        kwargs.pop(ignored, None)
    os.makedirs(output_path, exist_ok=True)
    staging = tempfile.mkdtemp(prefix=".parallax-", dir=output_path)
    try:
        posed = os.path.join(staging, "posed")
        reconstruction.write_binary(posed)
        models = _parallax.map(database_path, image_path, os.path.join(staging, "out"),
                               input_model=posed, fixed_poses=True, no_text=True, **kwargs)
        model_dir = os.path.join(staging, "out", "sparse", "0")
        for name in os.listdir(model_dir):
            os.replace(os.path.join(model_dir, name), os.path.join(output_path, name))
        return models[0]
    finally:
        shutil.rmtree(staging, ignore_errors=True)


# ----- Database ---------------------------------------------------------------------------------


class Database:
    """A COLMAP database (Parallax's or COLMAP's), read through sqlite3 in COLMAP's schema:
    pycolmap's Database(path) / Database.open(path), as a context manager too."""

    def __init__(self, path=None):
        self._connection = None
        if path is not None:
            self._open(path)

    @classmethod
    def open(cls, path):
        return cls(path)

    def _open(self, path):
        path = os.fspath(path)
        if not os.path.isfile(path):
            raise FileNotFoundError(f"{path}: database does not exist")
        self._connection = sqlite3.connect(f"file:{path}?mode=ro", uri=True)

    def close(self):
        if self._connection is not None:
            self._connection.close()
            self._connection = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _scalar(self, query, *args):
        return self._connection.execute(query, args).fetchone()[0]

    @property
    def num_images(self):
        return self._scalar("SELECT COUNT(*) FROM images")

    @property
    def num_cameras(self):
        return self._scalar("SELECT COUNT(*) FROM cameras")

    @property
    def num_keypoints(self):
        return self._scalar("SELECT COALESCE(SUM(rows), 0) FROM keypoints")

    @property
    def num_matches(self):
        return self._scalar("SELECT COALESCE(SUM(rows), 0) FROM matches")

    @property
    def num_verified_image_pairs(self):
        return self._scalar("SELECT COUNT(*) FROM two_view_geometries WHERE rows > 0")

    def exists_image(self, image_id):
        return self._scalar("SELECT COUNT(*) FROM images WHERE image_id = ?", image_id) > 0

    def read_all_images(self):
        """[{"image_id", "name", "camera_id"}] in id order."""
        rows = self._connection.execute(
            "SELECT image_id, name, camera_id FROM images ORDER BY image_id")
        return [{"image_id": i, "name": n, "camera_id": c} for i, n, c in rows]

    def _blob(self, table, image_id):
        """(rows, cols, bytes) of an image's row in `table`; None when it has none."""
        row = self._connection.execute(
            f"SELECT rows, cols, data FROM {table} WHERE image_id = ?", (image_id,)).fetchone()
        return None if row is None or row[0] == 0 else row

    def read_keypoints(self, image_id):
        """N x 2 pixel positions (COLMAP stores 2, 4 or 6 columns; the first two are x, y)."""
        row = self._blob("keypoints", image_id)
        if row is None:
            return np.zeros((0, 2))
        return np.frombuffer(row[2], dtype=np.float32).reshape(row[0], row[1])[:, :2].astype(float)

    def read_descriptors(self, image_id):
        row = self._blob("descriptors", image_id)
        if row is None:
            return np.zeros((0, 128), dtype=np.uint8)
        return np.frombuffer(row[2], dtype=np.uint8).reshape(row[0], row[1])

    def read_two_view_geometry_inliers(self, image_id1, image_id2):
        """The verified matches of a pair as an N x 2 array of keypoint indices (of image_id1,
        image_id2)."""
        swapped = image_id1 > image_id2
        first, second = (image_id2, image_id1) if swapped else (image_id1, image_id2)
        pair_id = first * 2147483647 + second
        row = self._connection.execute(
            "SELECT rows, data FROM two_view_geometries WHERE pair_id = ?", (pair_id,)).fetchone()
        if row is None or row[0] == 0:
            return np.zeros((0, 2), dtype=np.uint32)
        matches = np.frombuffer(row[1], dtype=np.uint32).reshape(row[0], 2)
        return matches[:, ::-1].copy() if swapped else matches.copy()


def _install():
    _patch_rigid3d()
    _patch_reconstruction()
    _patch_estimation_result()


_install()
