"""Every estimator on synthetic numpy data with exact ground truth, then noise and outliers."""

import numpy as np
import pytest

import parallax

K = np.array([[800.0, 0.0, 320.0], [0.0, 780.0, 240.0], [0.0, 0.0, 1.0]])


def rotation(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    angle = np.radians(degrees)
    skew = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew


def project(K, R, t, points):
    cam = points @ R.T + t
    pixels = cam @ K.T
    return pixels[:, :2] / pixels[:, 2:]


def angle_between(R1, R2):
    return np.degrees(np.arccos(np.clip((np.trace(R1.T @ R2) - 1) / 2, -1, 1)))


@pytest.fixture
def two_views():
    """200 points seen by two cameras; 0.3 px noise; the last 25 % replaced by outliers."""
    rng = np.random.default_rng(7)
    points = rng.uniform([-2, -2, 4], [2, 2, 8], size=(200, 3))
    R2, t2 = rotation([0.2, 1, 0.1], 8), np.array([-1.0, 0.1, 0.2])
    x1 = project(K, np.eye(3), np.zeros(3), points) + rng.normal(0, 0.3, (200, 2))
    x2 = project(K, R2, t2, points) + rng.normal(0, 0.3, (200, 2))
    outliers = np.arange(150, 200)
    x2[outliers] = rng.uniform([0, 0], [640, 480], size=(50, 2))
    truth = np.ones(200, bool)
    truth[outliers] = False
    return x1, x2, R2, t2, truth


def test_fundamental_matrix_separates_inliers(two_views):
    x1, x2, _, _, truth = two_views
    result = parallax.estimate_fundamental_matrix(x1, x2, max_error=2.0, seed=1)
    assert result.success and result.num_trials > 0
    assert result.model.shape == (3, 3)
    assert np.linalg.matrix_rank(result.model, tol=1e-9 * np.abs(result.model).max()) == 2
    assert result.inlier_mask[truth].mean() > 0.97
    assert result.inlier_mask[~truth].mean() < 0.1
    h1, h2 = np.c_[x1, np.ones(200)], np.c_[x2, np.ones(200)]
    Fx1, Ftx2 = h1 @ result.model.T, h2 @ result.model
    sampson = np.einsum("ij,ij->i", h2, Fx1) ** 2 / (
        Fx1[:, 0] ** 2 + Fx1[:, 1] ** 2 + Ftx2[:, 0] ** 2 + Ftx2[:, 1] ** 2)
    assert np.sqrt(np.median(sampson[truth])) < 0.5


def test_essential_matrix_recovers_the_relative_pose(two_views):
    x1, x2, R2, t2, truth = two_views
    direction = t2 / np.linalg.norm(t2)
    result = parallax.estimate_essential_matrix(x1, x2, K, max_error=2.0, seed=1)
    assert result.success
    assert result.inlier_mask[truth].mean() > 0.97 and result.inlier_mask[~truth].mean() < 0.1
    # 0.3 px of noise: the 8-point refit on the inliers is within half a degree.
    pose = result.cam2_from_cam1
    assert angle_between(pose.rotation, R2) < 0.5
    assert np.degrees(np.arccos(np.clip(pose.translation @ direction, -1, 1))) < 2.0
    # Without noise, E and the pose are exact (E up to scale and sign).
    rng = np.random.default_rng(4)
    points = rng.uniform([-2, -2, 4], [2, 2, 8], size=(50, 3))
    exact = parallax.estimate_essential_matrix(
        project(K, np.eye(3), np.zeros(3), points), project(K, R2, t2, points), K, seed=2)
    assert exact.inlier_mask.all()
    assert angle_between(exact.cam2_from_cam1.rotation, R2) < 1e-4
    assert np.allclose(exact.cam2_from_cam1.translation, direction, atol=1e-8)
    skew = np.array([[0, -direction[2], direction[1]], [direction[2], 0, -direction[0]],
                     [-direction[1], direction[0], 0]])
    E_true = skew @ R2
    E = exact.model / np.linalg.norm(exact.model) * np.linalg.norm(E_true)
    assert min(np.abs(E - E_true).max(), np.abs(E + E_true).max()) < 1e-8


def test_homography_of_a_plane(two_views):
    rng = np.random.default_rng(3)
    H = np.array([[1.1, 0.05, 20.0], [-0.03, 0.95, -10.0], [1e-4, 5e-5, 1.0]])
    x1 = rng.uniform([0, 0], [640, 480], size=(100, 2))
    mapped = np.c_[x1, np.ones(100)] @ H.T
    x2 = mapped[:, :2] / mapped[:, 2:] + rng.normal(0, 0.2, (100, 2))
    x2[80:] = rng.uniform([0, 0], [640, 480], size=(20, 2))
    result = parallax.estimate_homography(x1, x2, max_error=2.0, seed=2)
    assert result.success and result.inlier_mask[:80].all() and result.inlier_mask[80:].sum() <= 1
    estimated = result.model / result.model[2, 2]
    assert np.allclose(estimated, H, rtol=0.02, atol=0.5)


def test_absolute_pose_with_outliers():
    rng = np.random.default_rng(11)
    points = rng.uniform([-2, -2, 4], [2, 2, 8], size=(100, 3))
    R, t = rotation([1, 0.3, -0.2], 15), np.array([0.3, -0.2, 0.5])
    pixels = project(K, R, t, points) + rng.normal(0, 0.2, (100, 2))
    pixels[70:] = rng.uniform([0, 0], [640, 480], size=(30, 2))
    camera = parallax.Camera("PINHOLE", 640, 480, [K[0, 0], K[1, 1], K[0, 2], K[1, 2]])
    result = parallax.estimate_absolute_pose(pixels, points, camera, max_error=4.0, seed=3)
    assert result.success and result.inlier_mask[:70].all()
    assert angle_between(result.model.rotation, R) < 0.1
    assert np.linalg.norm(result.model.translation - t) < 0.01


def test_dlt_resection_splits_K_R_t():
    rng = np.random.default_rng(5)
    points = rng.uniform([-2, -2, 4], [2, 2, 8], size=(60, 3))
    K_true = np.array([[900.0, 2.0, 310.0], [0.0, 880.0, 250.0], [0.0, 0.0, 1.0]])
    R, t = rotation([0.1, -1, 0.4], 20), np.array([0.2, 0.4, -0.3])
    pixels = project(K_true, R, t, points)
    pixels[50:] += 50.0  # ten outliers
    result = parallax.dlt_resection(pixels, points, max_error=1.0, seed=4)
    assert result.success and result.inlier_mask[:50].all() and not result.inlier_mask[50:].any()
    assert result.model.shape == (3, 4)
    assert np.allclose(result.K, K_true, rtol=1e-6, atol=1e-4)
    assert np.allclose(result.R, R, atol=1e-8) and np.allclose(result.t, t, atol=1e-8)


def test_triangulation_is_exact_without_noise():
    rng = np.random.default_rng(2)
    points = rng.uniform([-1, -1, 4], [1, 1, 6], size=(30, 3))
    R2, t2 = rotation([0, 1, 0], 10), np.array([-0.8, 0, 0.1])
    P1 = K @ np.c_[np.eye(3), np.zeros(3)]
    P2 = K @ np.c_[R2, t2]
    triangulated = parallax.triangulate_points(
        P1, P2, project(K, np.eye(3), np.zeros(3), points), project(K, R2, t2, points))
    assert np.allclose(triangulated, points, atol=1e-8)


def test_too_few_points_fail_without_a_model():
    result = parallax.estimate_fundamental_matrix(np.zeros((5, 2)), np.zeros((5, 2)))
    assert not result.success and result.model is None and result.inlier_mask.shape == (5,)


@pytest.mark.parametrize("call, message", [
    (lambda: parallax.estimate_fundamental_matrix(np.zeros((10, 3)), np.zeros((10, 2))),
     r"points1: expected an N x 2 array, got shape \(10, 3\)"),
    (lambda: parallax.estimate_homography(np.zeros((10, 2)), np.zeros((9, 2))),
     r"points1, points2: different numbers of points \(10 and 9\)"),
    (lambda: parallax.estimate_essential_matrix(np.zeros((10, 2)), np.zeros((10, 2)), -K),
     "K1: not a calibration matrix"),
    (lambda: parallax.estimate_fundamental_matrix(np.zeros((10, 2)), np.zeros((10, 2)),
                                                  max_error=0),
     "max_error: must be positive"),
    (lambda: parallax.Camera("FISHEYE_42", 640, 480, [1, 2, 3]), "unknown camera model 'FISHEYE_42'"),
    (lambda: parallax.Camera("PINHOLE", 640, 480, [1, 2, 3]), "PINHOLE takes 4 parameters"),
    (lambda: parallax.extract_sift(np.zeros((8, 8), np.uint8)), "at least 16 x 16"),
    (lambda: parallax.extract_sift(np.zeros((32, 32), np.uint8), sift="vlfeat"),
     "sift must be 'native' or 'opencv'"),
])
def test_bad_input_raises_value_error(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_extract_sift_on_an_image(scene_dir):
    path = sorted(scene_dir.glob("*.png"))[0]
    image = parallax.read_image(path, grayscale=True)
    assert image.shape == (480, 640) and image.dtype == np.uint8
    keypoints, descriptors = parallax.extract_sift(image, max_features=1000)
    assert keypoints.shape[1] == 4 and keypoints.dtype == np.float32
    assert descriptors.shape == (keypoints.shape[0], 128) and descriptors.dtype == np.uint8
    assert 300 < keypoints.shape[0] <= 1000
    assert (keypoints[:, 0] > 0).all() and (keypoints[:, 0] < image.shape[1]).all()
    assert (keypoints[:, 2] > 0).all()
    # Float input in [0, 1] gives the same features; colour is converted to grey.
    assert np.array_equal(parallax.extract_sift(image / 255.0, max_features=1000)[0], keypoints)
    rgb = parallax.read_image(path)
    assert rgb.shape == (480, 640, 3)
    assert parallax.extract_sift(rgb, max_features=1000)[0].shape[0] > 300
    # OpenCV's SIFT finds most of the same places (its positions are a quarter pixel off).
    opencv_keypoints, _ = parallax.extract_sift(image, sift="opencv", max_features=1000)
    assert 300 < opencv_keypoints.shape[0] <= 1000
    offsets = np.linalg.norm(opencv_keypoints[:, None, :2] - keypoints[None, :, :2], axis=2)
    assert (offsets.min(axis=1) < 0.5).mean() > 0.6
