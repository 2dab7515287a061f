#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/geometry/rigid3.h"

namespace parallax {

// E = K2^T F K1.
Eigen::Matrix3d EssentialFromFundamental(const Eigen::Matrix3d& F, const Eigen::Matrix3d& K1,
                                         const Eigen::Matrix3d& K2);
// F = K2^-T E K1^-1.
Eigen::Matrix3d FundamentalFromEssential(const Eigen::Matrix3d& E, const Eigen::Matrix3d& K1,
                                         const Eigen::Matrix3d& K2);
// E = [t]_x R for x2 = R x1 + t.
Eigen::Matrix3d EssentialFromPose(const Rigid3d& cam2_from_cam1);

// The two rotations and the translation direction (unit norm) of E by SVD
// (Hartley & Zisserman, result 9.19): the four candidate poses are (R1|±t), (R2|±t).
void DecomposeEssentialMatrix(const Eigen::Matrix3d& E, Eigen::Matrix3d* R1, Eigen::Matrix3d* R2,
                              Eigen::Vector3d* t);

// Cheirality vote shared by the E and H decompositions: `rotations[c]` with the unit
// translation `translations[c]` or its negation, i.e. candidate 2 c + s is
// (rotations[c], s == 0 ? translations[c] : -translations[c]). Returns the candidate that puts
// the most triangulated correspondences in front of both cameras (and, when `points3D` is not
// null, those points in cam1's frame), or -1 when none puts any in front. Candidates with a
// non-finite rotation or translation get no votes.
int ChoosePoseByCheirality(const std::vector<Eigen::Matrix3d>& rotations,
                           const std::vector<Eigen::Vector3d>& translations,
                           const std::vector<Eigen::Vector2d>& points1,
                           const std::vector<Eigen::Vector2d>& points2,
                           std::vector<Eigen::Vector3d>* points3D);

// Chooses among the four poses of E the one that puts the most triangulated correspondences
// in front of both cameras (cheirality). points1/points2 are normalised image coordinates.
// Returns false when no pose has any point in front. `points3D` gets the points (in cam1's
// frame) that passed, when not null.
bool PoseFromEssentialMatrix(const Eigen::Matrix3d& E, const std::vector<Eigen::Vector2d>& points1,
                             const std::vector<Eigen::Vector2d>& points2, Rigid3d* cam2_from_cam1,
                             std::vector<Eigen::Vector3d>* points3D = nullptr);

}  // namespace parallax
