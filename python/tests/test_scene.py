"""Reconstruction, Camera, Image, Point3D and Rigid3d: model files, numpy views, conversions."""

import filecmp

import numpy as np
import pytest

import parallax

from conftest import SCENE_VIEWS


@pytest.fixture(scope="module")
def model_dir(reconstruction_dir):
    return reconstruction_dir[0] / "sparse" / "0"


def test_read_write_round_trips_through_the_cpp_writers(model_dir, tmp_path):
    model = parallax.Reconstruction.read(model_dir)
    model.write(tmp_path / "bin")
    model.write_text(tmp_path / "txt")
    for name in ("cameras", "images", "points3D"):
        assert filecmp.cmp(model_dir / f"{name}.bin", tmp_path / "bin" / f"{name}.bin", shallow=False)
        assert filecmp.cmp(model_dir / f"{name}.txt", tmp_path / "txt" / f"{name}.txt", shallow=False)
    # Text read back writes the same binary files.
    again = parallax.read_model(tmp_path / "txt")
    again.write(tmp_path / "bin2")
    for name in ("cameras", "images", "points3D"):
        assert filecmp.cmp(model_dir / f"{name}.bin", tmp_path / "bin2" / f"{name}.bin", shallow=False)


def test_bulk_arrays_agree_with_the_items(model_dir):
    model = parallax.read_model(model_dir)
    ids = model.reg_image_ids()
    centers = model.projection_centers()
    assert centers.shape == (len(ids), 3)
    for row, image_id in enumerate(ids):
        assert np.allclose(centers[row], model.images[image_id].projection_center())
    point_ids = model.point3D_ids()
    xyz, colors, errors = model.point3D_xyz(), model.point3D_colors(), model.point3D_errors()
    lengths = model.track_lengths()
    assert xyz.shape == (model.num_points3D(), 3) and colors.dtype == np.uint8
    for row in (0, len(point_ids) // 2, len(point_ids) - 1):
        point = model.points3D[int(point_ids[row])]
        assert np.array_equal(xyz[row], point.xyz) and np.array_equal(colors[row], point.color)
        assert errors[row] == point.error and lengths[row] == len(point.track)
    summary = model.summary()
    assert summary["points3D"] == model.num_points3D()
    assert summary["mean_track_length"] == pytest.approx(lengths.mean())
    assert sum(entry["points"] for entry in summary["track_length_histogram"]) == len(point_ids)


def test_items_are_dict_like_and_linked(model_dir):
    model = parallax.read_model(model_dir)
    assert len(model.images) == SCENE_VIEWS and set(model.images) == set(model.images.keys())
    image_id, image = model.images.items()[0]
    assert image_id in model.images and 10**9 not in model.images
    with pytest.raises(KeyError):
        model.images[10**9]
    ids = image.point3D_ids
    keypoints = image.keypoints
    assert keypoints.shape == (image.num_points2D, 2) and ids.shape == (image.num_points2D,)
    seen = np.flatnonzero(ids >= 0)
    assert len(seen) == image.num_points3D
    # The point's track holds this keypoint, and it reprojects near it.
    index = seen[0]
    point = model.points3D[int(ids[index])]
    assert any(e.image_id == image_id and e.point2D_idx == index for e in point.track.elements)
    camera = model.cameras[image.camera_id]
    in_cam = image.cam_from_world * point.xyz[None, :]
    assert np.linalg.norm(camera.img_from_cam(in_cam)[0] - keypoints[index]) < 2.0
    # Edits through a view change the model.
    model.images[image_id].name = "renamed.png"
    assert model.images[image_id].name == "renamed.png"


def test_camera_projection_round_trip_with_distortion():
    camera = parallax.Camera("SIMPLE_RADIAL", 640, 480, [500.0, 320.0, 240.0, -0.1])
    assert np.allclose(camera.K, [[500, 0, 320], [0, 500, 240], [0, 0, 1]])
    normalized = np.random.default_rng(1).uniform(-0.4, 0.4, size=(50, 2))
    pixels = camera.img_from_cam(normalized)
    assert np.allclose(camera.cam_from_img(pixels), normalized, atol=1e-9)
    assert np.allclose(camera.img_from_cam(np.c_[normalized * 2, np.full(50, 2.0)]), pixels)
    radius = np.linalg.norm(normalized, axis=1)
    expected = normalized * (1 - 0.1 * radius[:, None] ** 2) * 500 + [320, 240]
    assert np.allclose(pixels, expected)


WIDE_LENSES = [
    ("OPENCV_FISHEYE", 640, 640, [193.0, 195.0, 320.0, 320.0, 0.02, -0.005, 0.001, -0.0002], 95),
    ("FISHEYE", 640, 640, [193.0, 195.0, 320.0, 320.0], 95),
    ("RADIAL_FISHEYE", 640, 640, [193.0, 320.0, 320.0, 0.02, -0.005], 95),
    ("EUCM", 640, 480, [300.0, 305.0, 320.0, 240.0, 0.6, 1.1], 95),
    ("DIVISION", 640, 480, [500.0, 505.0, 320.0, 240.0, -0.05], 60),
    ("FULL_OPENCV", 640, 480,
     [800.0, 790, 320, 240, -0.08, 0.01, 0.001, -0.002, 0.001, 0.02, -0.01, 0.002], 35),
    ("EQUIRECTANGULAR", 2048, 1024, [2048.0, 1024.0], 175),
]


@pytest.mark.parametrize("model, width, height, params, max_angle", WIDE_LENSES)
def test_every_lens_projects_and_unprojects_rays(model, width, height, params, max_angle):
    camera = parallax.Camera(model, width, height, params)
    assert camera.model == model
    # Rays up to max_angle off the axis: beyond 90 degrees for the fisheyes, EUCM and the sphere.
    rng = np.random.default_rng(7)
    theta = np.radians(rng.uniform(0, max_angle, 200))
    phi = rng.uniform(0, 2 * np.pi, 200)
    rays = np.c_[np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]
    if model == "EQUIRECTANGULAR":
        rays = rays[np.abs(rays[:, 1]) < 0.99]  # Away from the poles.
    pixels = camera.img_from_cam(3.0 * rays)
    back = camera.cam_ray_from_img(pixels)
    assert np.allclose(np.linalg.norm(back, axis=1), 1.0)
    assert np.allclose(back, rays, atol=1e-9)
    expected = {"EQUIRECTANGULAR": "spherical", "EUCM": "perspective", "DIVISION": "perspective",
                "FULL_OPENCV": "perspective"}.get(model, "fisheye")
    assert camera.projection == expected


def test_the_sphere_has_no_focal_length():
    camera = parallax.Camera("EQUIRECTANGULAR", 2048, 1024, [2048.0, 1024.0])
    # The optical axis at the centre, +x at three quarters of the width.
    pixels = camera.img_from_cam(np.array([[0.0, 0, 1], [1.0, 0, 0]]))
    assert np.allclose(pixels, [[1024, 512], [1536, 512]])
    assert camera.focal_length == pytest.approx(2048 / (2 * np.pi))
    with pytest.raises(Exception, match="no focal length"):
        camera.K


def test_rigid_transform_conventions():
    angle = np.radians(30)
    R = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    transform = parallax.Rigid3d(R, np.array([1.0, 2.0, 3.0]))
    assert np.allclose(transform.quaternion, [np.cos(angle / 2), 0, 0, np.sin(angle / 2)])
    assert np.allclose(transform.matrix(), np.c_[R, [1, 2, 3]])
    points = np.array([[1.0, 0, 0], [0, 1, 2]])
    assert np.allclose(transform * points, points @ R.T + [1, 2, 3])
    identity = transform.inverse() * transform
    assert np.allclose(identity.rotation, np.eye(3)) and np.allclose(identity.translation, 0)
    with pytest.raises(ValueError, match="not a rotation matrix"):
        parallax.Rigid3d(2 * np.eye(3), np.zeros(3))


def test_export_ply(model_dir, tmp_path):
    model = parallax.read_model(model_dir)
    model.export_ply(tmp_path / "points.ply")
    header = (tmp_path / "points.ply").read_bytes().split(b"end_header\n")[0].decode()
    assert f"element vertex {model.num_points3D()}" in header


def test_undistort_writes_colmaps_dense_workspace(model_dir, scene_dir, tmp_path):
    count = parallax.undistort(model_dir, scene_dir, tmp_path / "dense", max_size=320)
    assert count == SCENE_VIEWS
    sparse = parallax.read_model(tmp_path / "dense" / "sparse")
    camera = next(iter(sparse.cameras.values()))
    assert camera.model == "PINHOLE" and max(camera.width, camera.height) == 320
    image = sparse.images[sparse.reg_image_ids()[0]]
    pixels = parallax.read_image(tmp_path / "dense" / "images" / image.name)
    assert pixels.shape == (camera.height, camera.width, 3)
    assert (tmp_path / "dense" / "stereo" / "patch-match.cfg").exists()


def test_export_model_for_nerfstudio(model_dir, tmp_path):
    import json
    parallax.export_model(model_dir, tmp_path / "transforms.json", format="nerfstudio")
    transforms = json.loads((tmp_path / "transforms.json").read_text())
    assert len(transforms["frames"]) == SCENE_VIEWS and transforms["camera_model"] == "OPENCV"
    assert (tmp_path / "sparse_pc.ply").exists()
    with pytest.raises(ValueError, match="unknown export format 'obj'"):
        parallax.export_model(model_dir, tmp_path / "x.obj", format="obj")


def test_pycolmap_habits_read_in_place_and_construct_from_a_path(model_dir, tmp_path):
    # pycolmap's Reconstruction(path), and rec.read(path) filling rec itself.
    from_path = parallax.Reconstruction(model_dir)
    in_place = parallax.Reconstruction()
    assert in_place.read(model_dir) is None
    assert in_place.num_reg_images() == from_path.num_reg_images() > 0
    assert in_place.num_points3D() == from_path.num_points3D() > 0
    # Parallax's own: on the class, read returns a new model.
    assert parallax.Reconstruction.read(model_dir).num_points3D() == from_path.num_points3D()
    in_place.write_binary(tmp_path / "bin")
    assert parallax.Reconstruction(tmp_path / "bin").num_points3D() == from_path.num_points3D()
    with pytest.raises(FileNotFoundError):
        parallax.Reconstruction(tmp_path / "missing")
