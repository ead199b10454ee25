#include "chasles/server/view_page.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <octomap/OcTree.h>

#include "chasles/collision/proximity.h"
#include "chasles/robot/error.h"
#include "chasles/server/convert.h"
#include "chasles/multi/team.h"
#include "chasles/server/convert_multi.h"
#include "view_assets.h"

namespace chasles {
namespace {

// ---- a small JSON writer (numbers with 6 significant digits: positions to the µm at metres) --

class Json {
 public:
  Json& Raw(const std::string& text) {
    out_ += text;
    return *this;
  }
  Json& Number(double value) {
    if (!std::isfinite(value)) return Raw("null");
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.6g", value == 0.0 ? 0.0 : value);
    return Raw(buffer);
  }
  Json& String(const std::string& text) {
    out_ += '"';
    for (const char c : text) {
      switch (c) {
        case '"': out_ += "\\\""; break;
        case '\\': out_ += "\\\\"; break;
        case '\n': out_ += "\\n"; break;
        case '<': out_ += "\\u003c"; break;  // never closes the page's <script>
        default:
          if (static_cast<unsigned char>(c) < 0x20) {
            char buffer[8];
            std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
            out_ += buffer;
          } else {
            out_ += c;
          }
      }
    }
    out_ += '"';
    return *this;
  }
  Json& Key(const char* key) {
    Comma();
    String(key);
    out_ += ':';
    fresh_ = true;  // the value follows without a comma
    return *this;
  }
  Json& Open(char bracket) {
    Comma();
    out_ += bracket;
    fresh_ = true;
    return *this;
  }
  Json& Close(char bracket) {
    out_ += bracket;
    fresh_ = false;
    return *this;
  }
  /// A value inside an array or after a key.
  Json& Value(double value) {
    Comma();
    fresh_ = false;
    return Number(value);
  }
  Json& Text(const std::string& text) {
    Comma();
    fresh_ = false;
    return String(text);
  }
  Json& Numbers(const double* values, std::size_t count) {
    Open('[');
    for (std::size_t i = 0; i < count; ++i) Value(values[i]);
    return Close(']');
  }
  Json& Vector(const Eigen::VectorXd& v) { return Numbers(v.data(), static_cast<std::size_t>(v.size())); }
  Json& Pose(const Eigen::Isometry3d& pose) {
    const Eigen::Quaterniond q(pose.linear());
    const double values[7] = {pose.translation().x(), pose.translation().y(), pose.translation().z(), q.w(), q.x(), q.y(), q.z()};
    return Numbers(values, 7);
  }
  const std::string& str() const { return out_; }

 private:
  void Comma() {
    if (!fresh_) out_ += ',';
    fresh_ = false;
  }
  std::string out_;
  bool fresh_ = true;
};

void ShapeJson(const Shape& shape, const Eigen::Isometry3d& pose, Json* json) {
  json->Open('{');
  switch (shape.type) {
    case ShapeType::kSphere:
      json->Key("type").Text("sphere").Key("radius").Value(shape.radius);
      break;
    case ShapeType::kBox:
      json->Key("type").Text("box").Key("size").Numbers(shape.size.data(), 3);
      break;
    case ShapeType::kCylinder:
      json->Key("type").Text("cylinder").Key("radius").Value(shape.radius).Key("length").Value(shape.length);
      break;
    case ShapeType::kCapsule:
      json->Key("type").Text("capsule").Key("radius").Value(shape.radius).Key("length").Value(shape.length);
      break;
    case ShapeType::kMesh: {
      json->Key("type").Text("mesh").Key("vertices").Open('[');
      if (shape.mesh) {
        for (const Eigen::Vector3d& v : shape.mesh->vertices) json->Value(v.x()).Value(v.y()).Value(v.z());
      }
      json->Close(']').Key("triangles").Open('[');
      if (shape.mesh) {
        for (const Eigen::Vector3i& t : shape.mesh->triangles) json->Value(t.x()).Value(t.y()).Value(t.z());
      }
      json->Close(']');
      break;
    }
  }
  json->Key("pose").Pose(pose);
  json->Close('}');
}

/// Indices of `count` items spread evenly over [0, n), first and last included.
std::vector<std::size_t> Spread(std::size_t n, std::size_t count) {
  std::vector<std::size_t> out;
  if (n == 0) return out;
  if (n <= count || count < 2) {
    for (std::size_t i = 0; i < n; ++i) out.push_back(i);
    return out;
  }
  for (std::size_t k = 0; k < count; ++k) out.push_back((k * (n - 1)) / (count - 1));
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// The display frames: samples at least 1/frame_rate apart (first and last kept).
std::vector<std::size_t> DisplayFrames(const std::vector<TrajectorySample>& samples, double frame_rate) {
  std::vector<std::size_t> out;
  double next = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (samples[i].t >= next || i + 1 == samples.size()) {
      out.push_back(i);
      next = samples[i].t + 1.0 / frame_rate;
    }
  }
  return out;
}

/// The link that leaves the trail: the last link with collision geometry (the tool end of a
/// chain), else the last link.
int TrailLink(const RobotModel& model) {
  for (int l = model.num_links() - 1; l >= 0; --l) {
    if (!model.links()[l].collision.empty()) return l;
  }
  return model.num_links() - 1;
}

struct Marker {
  std::string kind, text;
  Eigen::Vector3d position;
};

}  // namespace

std::string ViewDataJson(const ViewInput& input) {
  Json json;
  json.Open('{');
  json.Key("title").Text(input.title);
  double duration = 0.0;
  for (const ViewRobot& r : input.robots) {
    if (!r.samples.empty()) duration = std::max(duration, r.samples.back().t);
  }
  json.Key("duration").Value(duration);
  std::vector<Marker> markers;
  json.Key("robots").Open('[');
  for (const ViewRobot& r : input.robots) {
    const RobotModel& model = *r.robot.model;
    const RobotModel& drawn = r.robot.exact ? *r.robot.exact : model;  // meshes of a fitted robot
    json.Open('{').Key("name").Text(r.name).Key("links").Open('[');
    for (int l = 0; l < model.num_links(); ++l) {
      json.Open('{').Key("name").Text(model.links()[l].name).Key("shapes").Open('[');
      if (l < drawn.num_links()) {
        for (const Shape& shape : drawn.links()[l].collision) ShapeJson(shape, shape.pose, &json);
      }
      json.Close(']').Key("spheres").Open('[');
      for (const Shape& shape : model.links()[l].collision) {
        if (shape.type != ShapeType::kSphere) continue;
        const Eigen::Vector3d c = shape.pose.translation();
        const double sphere[4] = {c.x(), c.y(), c.z(), shape.radius};
        json.Numbers(sphere, 4);
      }
      json.Close(']').Close('}');
    }
    json.Close(']');

    // Frames: every link's world pose.
    const std::vector<std::size_t> frames = DisplayFrames(r.samples, input.frame_rate);
    const int trail = TrailLink(model);
    json.Key("frames").Open('{').Key("t").Open('[');
    for (std::size_t i : frames) json.Value(r.samples[i].t);
    json.Close(']').Key("poses").Open('[');
    std::vector<Eigen::Isometry3d> poses;
    for (std::size_t i : frames) {
      model.ForwardKinematics(r.samples[i].q, &poses);
      json.Open('[');
      for (const Eigen::Isometry3d& pose : poses) {
        const Eigen::Isometry3d world = r.base_pose * pose;
        const Eigen::Quaterniond q(world.linear());
        json.Value(world.translation().x()).Value(world.translation().y()).Value(world.translation().z());
        json.Value(q.w()).Value(q.x()).Value(q.y()).Value(q.z());
      }
      json.Close(']');
    }
    json.Close(']').Close('}');
    json.Key("trail_link").Value(trail);
    json.Key("waypoints").Open('[');
    for (const Eigen::VectorXd& q : r.waypoints) {
      if (q.size() != model.num_dofs()) continue;
      model.ForwardKinematics(q, &poses);
      const Eigen::Vector3d p = r.base_pose * poses[static_cast<std::size_t>(trail)].translation();
      json.Numbers(p.data(), 3);
    }
    json.Close(']');

    // Plots.
    json.Key("plot").Open('{').Key("joint_names").Open('[');
    for (const std::string& name : model.dof_names()) json.Text(name);
    json.Close(']');
    const std::vector<std::size_t> points = Spread(r.samples.size(), static_cast<std::size_t>(input.max_plot_points));
    json.Key("t").Open('[');
    for (std::size_t i : points) json.Value(r.samples[i].t);
    json.Close(']');
    const std::pair<const char*, Eigen::VectorXd TrajectorySample::*> series[] = {
        {"q", &TrajectorySample::q}, {"qd", &TrajectorySample::qd}, {"qdd", &TrajectorySample::qdd}};
    for (const auto& [key, member] : series) {
      json.Key(key).Open('[');
      for (std::size_t i : points) {
        const Eigen::VectorXd& v = r.samples[i].*member;
        json.Vector(v.size() == model.num_dofs() ? v : Eigen::VectorXd::Zero(model.num_dofs()));
      }
      json.Close(']');
    }
    json.Key("max_velocity").Vector(r.max_velocity);
    json.Key("max_acceleration").Vector(r.max_acceleration);
    json.Key("lower").Vector(model.lower_limits()).Key("upper").Vector(model.upper_limits());
    json.Close('}');
    json.Close('}');

    // The smallest clearance to the scene over the display frames, and where (a robot away from
    // the scene origin is placed by composing it: ObstacleProximity works in the model's frame).
    if (r.measure_clearance && input.scene && !input.scene->empty() && !r.samples.empty()) {
      std::shared_ptr<const RobotModel> placed = r.robot.model;
      if (!r.base_pose.matrix().isIdentity(0.0)) {
        PlacedRobot placement;
        placement.name = r.name;
        placement.model = r.robot.model;
        placement.base_pose = r.base_pose;
        placed = ComposeRobots({placement});
      }
      const ObstacleProximity proximity(placed, input.scene);
      std::vector<LinkProximity> nearest;
      double best = std::numeric_limits<double>::infinity();
      Marker marker;
      for (std::size_t i : frames) {
        proximity.Query(r.samples[i].q, std::numeric_limits<double>::infinity(), &nearest);
        for (const LinkProximity& p : nearest) {
          if (!p.found() || !(p.distance < best)) continue;
          best = p.distance;
          marker.kind = best <= 0.0 ? "failure" : "min_clearance";
          marker.position = 0.5 * (p.link_point + p.obstacle_point);
          char text[256];
          std::snprintf(text, sizeof text, "%s: '%s' %s '%s' at t = %.3f s (%.2f mm)", r.name.c_str(),
                        placed->links()[p.link].name.c_str(), best <= 0.0 ? "touches" : "nearest to",
                        p.obstacle_name.c_str(), r.samples[i].t, 1e3 * best);
          marker.text = text;
        }
      }
      if (std::isfinite(best)) markers.push_back(marker);
    }
  }
  json.Close(']');

  // The scene.
  json.Key("scene").Open('{').Key("objects").Open('[');
  if (input.scene) {
    for (const SceneObject& object : input.scene->objects()) {
      json.Open('{').Key("name").Text(object.name).Key("shape");
      ShapeJson(object.shape, object.shape.pose, &json);
      json.Close('}');
    }
  }
  json.Close(']').Key("voxels").Open('[');
  std::size_t voxels = 0;
  if (input.scene) {
    for (const OccupancyMap& map : input.scene->occupancy_maps()) {
      std::map<double, std::vector<Eigen::Vector3d>> by_size;  // pruned leaves are larger cubes
      for (auto it = map.tree->begin_leafs(), end = map.tree->end_leafs(); it != end; ++it) {
        if (!map.tree->isNodeOccupied(*it) || voxels >= input.max_voxels) continue;
        by_size[it.getSize()].push_back(map.pose * Eigen::Vector3d(it.getX(), it.getY(), it.getZ()));
        ++voxels;
      }
      for (const auto& [size, centres] : by_size) {
        json.Open('{').Key("name").Text(map.name).Key("size").Value(size).Key("centres").Open('[');
        for (const Eigen::Vector3d& c : centres) json.Value(c.x()).Value(c.y()).Value(c.z());
        json.Close(']').Close('}');
      }
    }
  }
  json.Close(']').Close('}');

  json.Key("markers").Open('[');
  for (const Marker& m : markers) {
    json.Open('{').Key("kind").Text(m.kind).Key("position").Numbers(m.position.data(), 3).Key("text").Text(m.text);
    json.Close('}');
  }
  json.Close(']');
  json.Key("info").Open('[');
  for (const std::string& line : input.info) json.Text(line);
  if (voxels >= input.max_voxels) json.Text("OctoMap voxels: the first " + std::to_string(input.max_voxels) + " drawn");
  json.Close(']');
  json.Close('}');
  return json.str();
}

std::string HtmlEscaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string ViewerLibraryJs() { return std::string(kThreeJs) + "\n" + std::string(kOrbitControlsJs) + "\n"; }

std::string ViewPageHtml(const std::string& data_json, const std::string& library_src) {
  std::string page(kViewerTemplate);
  const auto put = [&page](const std::string& placeholder, const std::string& text) {
    const std::size_t at = page.find(placeholder);
    if (at == std::string::npos) throw std::logic_error("the viewer template (clients/viewer/template.html) lacks " + placeholder);
    page.replace(at, placeholder.size(), text);
  };
  // Data first: the other placeholders cannot occur in it (the JSON escapes '<', and '/*@' cannot
  // start a JSON token), but they could occur in the scripts below.
  put("/*@DATA@*/", "const CHASLES_VIEW = " + data_json + ";");
  put("/*@CSS@*/", std::string(kViewerCss));
  if (library_src.empty()) {
    put("/*@THREE@*/", std::string(kThreeJs));
    put("/*@ORBIT@*/", std::string(kOrbitControlsJs));
  } else {  // the placeholder sits inside a <script>: close it, load the file, reopen
    put("/*@THREE@*/", "</script><script src=\"" + library_src + "\"></script><script>");
    put("/*@ORBIT@*/", "");
  }
  put("/*@VIEWER@*/", std::string(kViewerJs));
  return page;
}

// ---- from responses ---------------------------------------------------------------------------

namespace {

/// Samples of a returned trajectory, joints mapped by name onto the model's (the others held at
/// `held`, e.g. a planning group's robot outside the group); from the knots when there are no points.
std::vector<TrajectorySample> SamplesOf(const v1::JointTrajectory& trajectory, const v1::TrajectoryKnots& knots,
                                        const RobotModel& model, const Eigen::VectorXd& held) {
  const int n = model.num_dofs();
  const Eigen::VectorXd base = held.size() == n ? held : Eigen::VectorXd::Zero(n);
  const auto index_of = [&](const google::protobuf::RepeatedPtrField<std::string>& names) {
    std::vector<int> index;
    if (names.empty()) {
      for (int i = 0; i < n; ++i) index.push_back(i);
      return index;
    }
    for (const std::string& name : names) {
      const auto it = std::find(model.dof_names().begin(), model.dof_names().end(), name);
      if (it == model.dof_names().end()) {
        ThrowInvalid("trajectory.joint_names has '" + name + "', not a joint of robot '" + model.name() + "'");
      }
      index.push_back(static_cast<int>(it - model.dof_names().begin()));
    }
    return index;
  };
  // The samples over the trajectory's own joints: its points, or its knots as the exact
  // constant-acceleration trajectory they describe, sampled at 10 ms.
  std::vector<TrajectorySample> own;
  std::vector<int> index;
  if (trajectory.points_size() > 0) {
    index = index_of(trajectory.joint_names());
    for (const v1::TrajectoryPoint& p : trajectory.points()) {
      if (p.positions_size() != static_cast<int>(index.size())) {
        ThrowInvalid("trajectory point at t = " + FormatNumber(p.time_from_start()) + " has " +
                     std::to_string(p.positions_size()) + " positions for " + std::to_string(index.size()) + " joints");
      }
      const auto values = [&p](const google::protobuf::RepeatedField<double>& field) {
        Eigen::VectorXd v = Eigen::VectorXd::Zero(p.positions_size());
        if (field.size() == p.positions_size()) v = Eigen::Map<const Eigen::VectorXd>(field.data(), field.size());
        return v;
      };
      TrajectorySample s;
      s.t = p.time_from_start();
      s.q = values(p.positions());
      s.qd = values(p.velocities());
      s.qdd = values(p.accelerations());
      own.push_back(std::move(s));
    }
  } else if (knots.times_size() > 0) {
    index = index_of(knots.joint_names());
    const int m = static_cast<int>(index.size());
    if (knots.positions_size() != knots.times_size() * m || knots.velocities_size() != knots.times_size() * m) {
      ThrowInvalid("knots: " + std::to_string(knots.times_size()) + " times for " + std::to_string(knots.positions_size()) +
                   " positions and " + std::to_string(knots.velocities_size()) + " velocities of " + std::to_string(m) +
                   " joints");
    }
    const auto knot = [&](const google::protobuf::RepeatedField<double>& values, int k) {
      return Eigen::Map<const Eigen::VectorXd>(values.data() + static_cast<std::ptrdiff_t>(k) * m, m).eval();
    };
    std::vector<TimedTrajectory::Piece> pieces;
    for (int k = 0; k + 1 < knots.times_size(); ++k) {
      TimedTrajectory::Piece piece;
      piece.t0 = knots.times(k);
      piece.duration = knots.times(k + 1) - knots.times(k);
      piece.coefficients.resize(m, 3);
      piece.coefficients.col(0) = knot(knots.positions(), k);
      piece.coefficients.col(1) = knot(knots.velocities(), k);
      piece.coefficients.col(2) = piece.duration > 0.0
                                      ? ((knot(knots.velocities(), k + 1) - knot(knots.velocities(), k)) / (2.0 * piece.duration)).eval()
                                      : Eigen::VectorXd::Zero(m);
      pieces.push_back(std::move(piece));
    }
    const Eigen::VectorXd end = knot(knots.positions(), knots.times_size() - 1);
    if (pieces.empty()) {
      TimedTrajectory::Piece stand;
      stand.coefficients = end;
      pieces.push_back(std::move(stand));
    }
    own = TimedTrajectory(std::move(pieces), end).Sample(0.01);
  }
  // Onto the model's joints, the others held.
  std::vector<TrajectorySample> samples;
  for (const TrajectorySample& o : own) {
    TrajectorySample s;
    s.t = o.t;
    s.q = base;
    s.qd = Eigen::VectorXd::Zero(n);
    s.qdd = Eigen::VectorXd::Zero(n);
    for (std::size_t j = 0; j < index.size(); ++j) {
      s.q[index[j]] = o.q[static_cast<Eigen::Index>(j)];
      s.qd[index[j]] = o.qd[static_cast<Eigen::Index>(j)];
      s.qdd[index[j]] = o.qdd[static_cast<Eigen::Index>(j)];
    }
    samples.push_back(std::move(s));
  }
  return samples;
}

JointPath PathOf(const google::protobuf::RepeatedPtrField<v1::JointState>& path) {
  JointPath out;
  for (const v1::JointState& state : path) {
    Eigen::VectorXd q(state.positions_size());
    for (int i = 0; i < q.size(); ++i) q[i] = state.positions(i);
    out.push_back(q);
  }
  return out;
}

Eigen::VectorXd Values(const google::protobuf::RepeatedField<double>& values) {
  Eigen::VectorXd v(values.size());
  for (int i = 0; i < values.size(); ++i) v[i] = values[i];
  return v;
}

/// The limits a response says it was timed with (TrajectoryLimits), for the robot's joints.
void LimitsOf(const v1::TrajectoryLimits& limits, ViewRobot* robot) {
  const int n = robot->robot.model->num_dofs();
  if (limits.max_velocity_size() == n) robot->max_velocity = Values(limits.max_velocity());
  if (limits.max_acceleration_size() == n) robot->max_acceleration = Values(limits.max_acceleration());
}

std::string Seconds(double s) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3f s", s);
  return buffer;
}

void VerificationInfo(const v1::Verification& v, std::vector<std::string>* info) {
  if (v.collision_guarantee().empty()) return;
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "verified: %s, max |qd|/v %.3f, max |qdd|/a %.3f", v.collision_guarantee().c_str(),
                v.max_velocity_ratio(), v.max_acceleration_ratio());
  info->push_back(buffer);
  if (!v.collision_guarantee_reason().empty()) info->push_back(v.collision_guarantee_reason());
}

}  // namespace

ViewInput ViewOfPlan(ModelStore& store, const v1::PlanRequest& request, const v1::PlanResponse& response) {
  ViewInput view;
  ViewRobot robot;
  robot.name = "robot";
  robot.robot = RobotOfRequest(store, request);
  std::vector<std::string> ignored;
  robot.robot = store.Carrying(robot.robot, request.attached_objects(), "attached_objects", &ignored);
  if (request.has_workcell() && request.workcell().has_base_pose()) {
    robot.base_pose = PoseFromProto(request.workcell().base_pose(), "workcell.base_pose");
  }
  view.scene = SceneOfRequest(store, request).scene;
  const Eigen::VectorXd start = Values(request.start().positions());
  robot.samples = SamplesOf(response.trajectory(), response.knots(), *robot.robot.model, start);
  if (request.group().empty()) robot.waypoints = PathOf(response.path());
  LimitsOf(response.limits(), &robot);
  view.title = "Plan " + (response.request_id().empty() ? std::string("") : response.request_id() + " ") + "— " +
               v1::PlanOutcome_Name(response.outcome()) + (response.duration() > 0.0 ? ", " + Seconds(response.duration()) : "");
  view.info.push_back("outcome " + v1::PlanOutcome_Name(response.outcome()));
  if (!response.message().empty()) view.info.push_back(response.message());
  VerificationInfo(response.verification(), &view.info);
  if (response.quality().min_clearance() != 0.0) {  // 0: not measured (plans in space-time)
    char buffer[128];
    std::snprintf(buffer, sizeof buffer, "min clearance (bound) %.2f mm", 1e3 * response.quality().min_clearance());
    view.info.push_back(buffer);
  }
  for (const std::string& warning : response.warnings()) view.info.push_back("warning: " + warning);
  view.robots.push_back(std::move(robot));
  // Moving obstacles are drawn as robots of their own (free flyers carrying their shapes).
  for (const MovingObstacle& obstacle : MovingObstaclesFromProto(request.moving_obstacles())) {
    const CommittedMotion motion = MotionOfObstacle(obstacle, "moving_obstacles");
    ViewRobot moving;
    moving.name = obstacle.name;
    moving.measure_clearance = false;
    moving.robot.model = motion.placement.model;
    const double end = std::max(view.robots.front().samples.empty() ? 0.0 : view.robots.front().samples.back().t,
                                motion.trajectory.duration());
    moving.samples = motion.trajectory.Sample(0.01);
    if (moving.samples.back().t < end) {
      TrajectorySample last = moving.samples.back();
      last.t = end;
      moving.samples.push_back(last);
    }
    view.robots.push_back(std::move(moving));
  }
  return view;
}

ViewInput ViewOfOptimize(ModelStore& store, const v1::OptimizeRequest& request, const v1::OptimizeResponse& response) {
  ViewInput view;
  ViewRobot robot;
  robot.name = "robot";
  robot.robot = RobotOfRequest(store, request);
  view.scene = SceneOfRequest(store, request).scene;
  Eigen::VectorXd held;
  if (request.path_size() > 0) held = Values(request.path(0).positions());
  robot.samples = SamplesOf(response.trajectory(), response.knots(), *robot.robot.model, held);
  if (request.group().empty()) robot.waypoints = PathOf(request.path());
  LimitsOf(response.limits(), &robot);
  view.title = "Optimize " + (response.request_id().empty() ? std::string("") : response.request_id() + " ") + "— " +
               v1::PlanOutcome_Name(response.outcome()) + (response.duration() > 0.0 ? ", " + Seconds(response.duration()) : "");
  view.info.push_back("outcome " + v1::PlanOutcome_Name(response.outcome()));
  if (!response.message().empty()) view.info.push_back(response.message());
  VerificationInfo(response.verification(), &view.info);
  view.robots.push_back(std::move(robot));
  return view;
}

ViewInput ViewOfCoordinate(ModelStore& store, const v1::CoordinateRequest& request,
                           const v1::CoordinateResponse& response) {
  ViewInput view;
  view.scene = SceneOfRequest(store, request).scene;
  std::map<std::string, const v1::TeamRobot*> asked;
  for (const v1::TeamRobot& r : request.robots()) asked[r.name()] = &r;
  for (const v1::RobotTrajectory& t : response.robots()) {
    const auto it = asked.find(t.name());
    if (it == asked.end()) ThrowInvalid("response robot '" + t.name() + "' is not in the request");
    const v1::TeamRobot& r = *it->second;
    ViewRobot robot;
    robot.name = t.name();
    robot.robot = RobotOfRequest(store, r, "robots[" + t.name() + "].robot");
    if (r.has_base_pose()) robot.base_pose = PoseFromProto(r.base_pose(), "robots[" + t.name() + "].base_pose");
    robot.samples = SamplesOf(t.trajectory(), t.knots(), *robot.robot.model, Values(r.start().positions()));
    if (r.group().empty()) robot.waypoints = PathOf(t.path());
    view.robots.push_back(std::move(robot));
  }
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "Coordinate — %s, %zu robots, makespan %.3f s",
                v1::PlanOutcome_Name(response.outcome()).c_str(), view.robots.size(), response.makespan());
  view.title = buffer;
  view.info.push_back("method " + response.method());
  if (!response.message().empty()) view.info.push_back(response.message());
  return view;
}

}  // namespace chasles
