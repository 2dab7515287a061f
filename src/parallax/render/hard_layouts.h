#pragma once

#include <random>
#include <vector>

#include "parallax/geometry/rigid3.h"
#include "parallax/render/scene_model.h"

namespace parallax {

struct SyntheticSceneOptions;

// View layouts of the temple scene that make incremental SfM fail in the ways real scenes do
// (issue 58, "Hard real scenes"): each is named for the failure it provokes. All are in
// metres, world z up, and keep the default 58 degree framing by moving the cameras away with
// the focal length, except the street, where a pedestrian's eye height is what matters.

// kStreet: two rows of temples face each other across a street; the camera walks down its
// middle at eye height, looking forward (small triangulation angles everywhere).
constexpr double kStreetRowSpacing = 24.0;  // Between the rows' centre lines.
constexpr double kStreetStep = 1.0;         // Between consecutive views.
constexpr double kStreetEyeHeight = 1.6;
// Where the walk starts along the street (x), a few metres before the first temples.
constexpr double kStreetStart = -6.0;
// How far the street reaches past the last view, so that no view looks down an empty one.
constexpr double kStreetLookahead = 90.0;

// kTwin: two identical temples (SceneModelOptions::identical_temples) seen from a stadium
// around the pair, so that views of one match views of the other.
constexpr double kTwinSpacing = 36.0;

// kWeak: arcs around two temples far apart, joined by a few distant views that see both.
constexpr double kWeakSpacing = 50.0;
// Distance from the temples' axis of the views between them.
constexpr double kWeakBridgeDistance = 56.0;

// The scene each layout looks at.
SceneModelOptions StreetSceneOptions(const SyntheticSceneOptions& options);
SceneModelOptions TwinSceneOptions(const SyntheticSceneOptions& options);
SceneModelOptions WeakSceneOptions(const SyntheticSceneOptions& options);

// Number of views of kWeak between the two arcs: 2 to 4.
int WeakBridgeViewCount(int num_views);

// cam_from_world of every view in walking or flying order, drawing the jitter from `engine`.
// The street: a pedestrian's phone, about 1 m apart, yaw swaying a few degrees with the gait,
// pitched a little down, with a little roll.
std::vector<Rigid3d> StreetWalkPoses(const SyntheticSceneOptions& options, std::mt19937_64* engine);
// The twins: evenly along a stadium (two half circles joined by straight sides) around the
// pair, each view looking at the nearest point of the segment between the temples' centres.
std::vector<Rigid3d> TwinOrbitPoses(const SyntheticSceneOptions& options, std::mt19937_64* engine);
// The weak link: an arc around temple 0 on the side facing temple 1 (looking away from it),
// the bridge views, then the same arc around temple 1. The arcs stop short of the far sides,
// whose views would see the other temple behind their own.
std::vector<Rigid3d> WeakLinkPoses(const SyntheticSceneOptions& options, std::mt19937_64* engine);

}  // namespace parallax
