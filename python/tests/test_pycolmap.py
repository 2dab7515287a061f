"""pycolmap's habits: snippets as pycolmap's README and documentation write them, run with
`import parallax as pycolmap` and unchanged otherwise."""

import numpy as np
import pytest

import parallax as pycolmap


def test_readme_pipeline(scene_dir, tmp_path):
    # pycolmap's README, "Reconstruction pipeline".
    output_path = tmp_path / "out"
    output_path.mkdir()
    mvs_path = output_path / "mvs"
    database_path = output_path / "database.db"
    pycolmap.extract_features(database_path, scene_dir)
    pycolmap.match_exhaustive(database_path)
    maps = pycolmap.incremental_mapping(database_path, scene_dir, output_path)
    maps[0].write(output_path)
    pycolmap.undistort_images(mvs_path, output_path, scene_dir)

    assert isinstance(maps, dict) and list(maps) == [0]
    assert maps[0].num_reg_images() == 20
    # Each model in <output_path>/<k>/, as COLMAP lays it out; nothing left beside.
    assert pycolmap.Reconstruction(output_path / "0").num_reg_images() == 20
    assert sorted(p.name for p in output_path.iterdir() if p.is_dir()) == ["0", "mvs"]
    assert (mvs_path / "sparse" / "cameras.bin").exists()
    with pycolmap.Database(database_path) as db:
        assert db.num_images == 20
        assert db.num_verified_image_pairs > 0
        images = db.read_all_images()
        first, second = images[0]["image_id"], images[1]["image_id"]
        keypoints = db.read_keypoints(first)
        assert keypoints.shape[1] == 2 and len(keypoints) > 100
        assert db.read_descriptors(first).shape == (len(keypoints), 128)
        inliers = db.read_two_view_geometry_inliers(first, second)
        assert len(inliers) > 0
        assert np.array_equal(db.read_two_view_geometry_inliers(second, first), inliers[:, ::-1])


def test_extract_features_takes_both_argument_orders(scene_dir, tmp_path):
    parallax_order = pycolmap.extract_features(scene_dir, tmp_path / "a.db")
    pycolmap_order = pycolmap.extract_features(tmp_path / "b.db", scene_dir,
                                               camera_mode=pycolmap_camera_mode("SINGLE"))
    keywords = pycolmap.extract_features(database_path=tmp_path / "c.db", image_path=scene_dir)
    assert parallax_order.num_extracted == pycolmap_order.num_extracted == 20
    assert keywords.num_extracted == 20
    assert pycolmap.Database(tmp_path / "b.db").num_cameras == 1


def pycolmap_camera_mode(name):
    """pycolmap.CameraMode.SINGLE and friends are enums; their name is what is read."""
    return type("CameraMode", (), {"name": name})()


def test_reading_a_reconstruction(reconstruction_dir, tmp_path):
    # pycolmap's README, "Reconstruction object".
    output, _ = reconstruction_dir
    reconstruction = pycolmap.Reconstruction(output / "sparse" / "0")
    print(reconstruction.summary())
    for image_id, image in reconstruction.images.items():
        print(image_id, image)
    for point3D_id, point3D in reconstruction.points3D.items():
        print(point3D_id, point3D)
    for camera_id, camera in reconstruction.cameras.items():
        print(camera_id, camera)
    reconstruction.write(tmp_path / "copy")
    reconstruction.export_PLY(tmp_path / "rec.ply")
    assert pycolmap.Reconstruction(tmp_path / "copy").num_points3D() == reconstruction.num_points3D()
    assert (tmp_path / "rec.ply").stat().st_size > 0

    image = reconstruction.images[reconstruction.reg_image_ids()[0]]
    # pycolmap 3.12 calls cam_from_world; earlier versions read it: both work.
    pose = image.cam_from_world()
    assert np.allclose(pose.rotation.matrix(), image.cam_from_world.rotation)
    assert np.allclose(pose.matrix()[:, 3], pose.translation)
    # The rotation's quaternion in pycolmap's x, y, z, w order, and back.
    quat = pose.rotation.quat
    assert quat.shape == (4,) and np.isclose(np.linalg.norm(quat), 1)
    assert np.allclose(pycolmap.Rotation3d(quat).matrix(), pose.rotation.matrix())
    camera = reconstruction.cameras[image.camera_id]
    assert np.allclose(camera.calibration_matrix(), camera.K)


def test_rigid3d_from_rotation3d():
    rotation = pycolmap.Rotation3d(np.array([0, 0, np.sin(0.25), np.cos(0.25)]))  # 0.5 rad about z
    rigid = pycolmap.Rigid3d(rotation=rotation, translation=np.array([1.0, 2.0, 3.0]))
    assert np.allclose(rigid.rotation.matrix()[:2, :2],
                       [[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]])
    assert np.allclose(rigid.rotation.inverse().matrix() @ rigid.rotation.matrix(), np.eye(3))
    points = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    assert np.allclose(rotation * points, points @ rotation.matrix().T)
    with pytest.raises(ValueError):
        pycolmap.Rotation3d(np.zeros(5))


def _two_views():
    rng = np.random.default_rng(4)
    points3D = np.column_stack([rng.uniform(-1, 1, 200), rng.uniform(-1, 1, 200),
                                rng.uniform(4, 6, 200)])
    camera = pycolmap.Camera(model="SIMPLE_RADIAL", width=640, height=480,
                             params=[500.0, 320.0, 240.0, 0.05])
    angle = 0.1
    rotation = np.array([[np.cos(angle), 0, np.sin(angle)], [0, 1, 0],
                         [-np.sin(angle), 0, np.cos(angle)]])
    translation = np.array([-0.5, 0.0, 0.05])
    in_cam2 = points3D @ rotation.T + translation
    points1 = camera.img_from_cam(points3D)
    points2 = camera.img_from_cam(in_cam2)
    return camera, points3D, points1, points2, rotation, translation


def test_estimators_return_pycolmaps_keys():
    camera, points3D, points1, points2, rotation, translation = _two_views()
    # Absolute pose: answer["cam_from_world"], ["num_inliers"], ["inlier_mask"].
    answer = pycolmap.estimate_absolute_pose(points2, points3D, camera,
                                             estimation_options={"ransac": {"max_error": 4.0}})
    assert answer is not None and answer
    assert np.allclose(answer["cam_from_world"].rotation.matrix(), rotation, atol=1e-6)
    assert np.allclose(answer["cam_from_world"].translation, translation, atol=1e-6)
    assert answer["num_inliers"] == 200 and answer["inlier_mask"].all()
    # Essential matrix from two cameras (their distortion undone first): the relative pose.
    answer = pycolmap.estimate_essential_matrix(points1, points2, camera, camera)
    assert answer["num_inliers"] == 200
    assert np.allclose(answer["cam2_from_cam1"].rotation.matrix(), rotation, atol=1e-5)
    direction = answer["cam2_from_cam1"].translation
    assert np.allclose(direction / np.linalg.norm(direction),
                       translation / np.linalg.norm(translation), atol=1e-5)
    assert answer["E"].shape == (3, 3)
    # Fundamental and homography under their pycolmap names (0.x names too).
    assert pycolmap.estimate_fundamental_matrix(points1, points2)["F"].shape == (3, 3)
    assert pycolmap.fundamental_matrix_estimation is pycolmap.estimate_fundamental_matrix
    assert pycolmap.homography_matrix_estimation(points1, points2)["H"].shape == (3, 3)
    with pytest.raises(KeyError):
        answer["no_such_key"]


def test_triangulate_points_into_fixed_poses(reconstruction_dir, scene_dir, tmp_path):
    # pycolmap.triangulate_points(reconstruction, database_path, image_path, output_path).
    output, _ = reconstruction_dir
    reconstruction = pycolmap.Reconstruction(output / "sparse" / "0")
    triangulated = pycolmap.triangulate_points(reconstruction, output / "database.db", scene_dir,
                                               tmp_path / "triangulated")
    assert triangulated.num_points3D() > reconstruction.num_points3D() / 2
    written = pycolmap.Reconstruction(tmp_path / "triangulated")
    assert written.num_points3D() == triangulated.num_points3D()
    for image_id in reconstruction.reg_image_ids():
        given = reconstruction.images[image_id].cam_from_world
        kept = written.images[image_id].cam_from_world
        assert np.array_equal(given.matrix(), kept.matrix())
    # Parallax's own form is unchanged: two projection matrices and matched points.
    P1 = np.hstack([np.eye(3), np.zeros((3, 1))])
    P2 = np.hstack([np.eye(3), np.array([[-1.0], [0], [0]])])
    point = np.array([0.2, -0.1, 4.0])
    x1 = (point / point[2])[:2]
    x2 = ((point + [-1.0, 0, 0]) / point[2])[:2]
    assert np.allclose(pycolmap.triangulate_points(P1, P2, x1[None], x2[None])[0], point)
