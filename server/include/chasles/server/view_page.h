#pragma once
/// \file
/// The trajectory viewer page (clients/viewer/): the view data of a response — every robot's
/// link shapes and collision spheres, its link poses at display frames (forward kinematics),
/// its trail, waypoints and limit plots, the scene (primitives, meshes, OctoMap voxels) and the
/// minimum-clearance point — and the self-contained HTML page around it (three.js, the viewer's
/// script and style inlined: it opens from disk with no network). Used by `chasles view` and by
/// the server's --http-listen.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "chasles/collision/scene.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/robot/joint_path.h"
#include "chasles/server/model_store.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// One robot of a view.
struct ViewRobot {
  std::string name;
  StoredRobot robot;  ///< model (what is checked), exact (a fitted robot's meshes), fit
  Eigen::Isometry3d base_pose = Eigen::Isometry3d::Identity();  ///< in the scene frame
  std::vector<TrajectorySample> samples;  ///< as returned (t, q, qd, qdd)
  JointPath waypoints;                    ///< the path, when the response has one
  Eigen::VectorXd max_velocity, max_acceleration;  ///< the limits timed with; empty = unknown
  bool measure_clearance = true;  ///< false: not checked against the scene (a moving obstacle)
};

struct ViewInput {
  std::string title;
  std::vector<std::string> info;  ///< lines for the side panel
  std::vector<ViewRobot> robots;
  std::shared_ptr<const Scene> scene;
  double frame_rate = 100.0;      ///< [1/s] display frames at most this dense
  int max_plot_points = 2000;
  std::size_t max_voxels = 200000;
};

/// The view data (clients/viewer/README.md) as JSON. The minimum-clearance point is measured
/// here (collision/ ObstacleProximity over the display frames, each robot against the scene).
std::string ViewDataJson(const ViewInput& input);

/// The page: clients/viewer/template.html with three.js (Debian's libjs-three), OrbitControls,
/// viewer.css, viewer.js and `data_json` inlined.
/// With `library_src` (e.g. "three.js"), three.js and OrbitControls are not inlined but loaded
/// from that file, written once beside many pages (ViewerLibraryJs): `chasles bench --views`.
std::string ViewPageHtml(const std::string& data_json, const std::string& library_src = "");
/// three.js and OrbitControls, for `library_src`.
std::string ViewerLibraryJs();

/// `text` safe in HTML text and attribute values (& < > " escaped): for the pages that link views.
std::string HtmlEscaped(const std::string& text);

/// The view of a Plan (its request gives robot and scene; none = the store's defaults),
/// Optimize or Coordinate exchange. Robots and scenes are resolved through `store` as the server
/// resolves them. \throws Error naming the field when the request and response do not fit
/// (e.g. a trajectory with 6 joints for a robot with 7).
ViewInput ViewOfPlan(ModelStore& store, const v1::PlanRequest& request, const v1::PlanResponse& response);
ViewInput ViewOfOptimize(ModelStore& store, const v1::OptimizeRequest& request, const v1::OptimizeResponse& response);
ViewInput ViewOfCoordinate(ModelStore& store, const v1::CoordinateRequest& request,
                           const v1::CoordinateResponse& response);

}  // namespace chasles
