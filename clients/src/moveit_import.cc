#include "moveit_import.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "chasles/collision/scene.h"
#include "chasles/robot/error.h"
#include "chasles/robot/robot_model.h"
#include "chasles/server/convert.h"
#include "chasles/server/default_assets.h"

// Design notes
// ------------
// * One Value (a YAML node plus its key path and the file name) does every read, so every error
//   names the file, the key path with indices, the value and the rule in one place. Nodes are
//   only ever read through const references: yaml-cpp's non-const operator[] inserts keys.
// * Missing optional fields take the moveit_msgs defaults (0, empty, identity for an object
//   pose); a key that the conversion cannot do without (an object id, a primitive's type and
//   dimensions, a joint constraint's joint and position) is a named error.
// * Nothing that changes the problem is dropped silently: shapes, operations, constraints and
//   attached objects that Chasles cannot represent are errors naming what is supported.

namespace chasles::moveit {
namespace {

constexpr double kPi = 3.14159265358979323846;

constexpr double kMaxGoalTolerance = 0.1;  // JointGoal.tolerance range [rad]
constexpr double kMaxTimeBudget = 600.0;   // PlanRequest.time_budget range [s]

/// A YAML node with the path that led to it, for messages.
class Value {
 public:
  Value(YAML::Node node, std::string path, const std::string* source)
      : node_(std::move(node)), path_(std::move(path)), source_(source) {}

  const std::string& path() const { return path_; }
  const std::string& source() const { return *source_; }
  const YAML::Node& node() const { return node_; }
  bool IsNull() const { return !node_.IsDefined() || node_.IsNull(); }

  /// Throws Error(kInvalidArgument) "<source>: <path> <rule>".
  [[noreturn]] void Fail(const std::string& rule) const { ThrowInvalid(source() + ": " + path_ + " " + rule); }

  /// The key's value, or nullopt when the key is absent or null. The node must be a map (or null).
  std::optional<Value> Find(const std::string& key) const {
    if (IsNull()) return std::nullopt;
    RequireMap();
    const YAML::Node& self = node_;
    const YAML::Node child = self[key];
    if (!child.IsDefined() || child.IsNull()) return std::nullopt;
    return Value(child, Join(key), source_);
  }

  /// The key's value; a missing key is an error.
  Value Get(const std::string& key) const {
    if (IsNull()) Fail("is empty: it needs the key '" + key + "'");
    std::optional<Value> child = Find(key);
    if (!child) ThrowInvalid(source() + ": " + Join(key) + " is missing");
    return *child;
  }

  /// The elements of a sequence; null = none.
  std::vector<Value> Items() const {
    std::vector<Value> items;
    if (IsNull()) return items;
    if (!node_.IsSequence()) Fail("= " + Describe() + " must be a list");
    items.reserve(node_.size());
    for (std::size_t i = 0; i < node_.size(); ++i) {
      const YAML::Node& self = node_;
      items.emplace_back(self[i], path_ + "[" + std::to_string(i) + "]", source_);
    }
    return items;
  }

  /// Number of elements of a list (0 for null).
  std::size_t Count() const { return Items().size(); }

  /// A finite number.
  double Number() const {
    double value = 0.0;
    if (!node_.IsScalar() || !YAML::convert<double>::decode(node_, value)) Fail("= " + Describe() + " is not a number");
    if (!std::isfinite(value)) Fail("= " + node_.Scalar() + " must be finite");
    return value;
  }

  /// A whole number within [lo, hi].
  long long Integer(long long lo, long long hi) const {
    const double value = Number();
    if (value != std::floor(value) || value < static_cast<double>(lo) || value > static_cast<double>(hi)) {
      Fail("= " + node_.Scalar() + " must be a whole number within [" + std::to_string(lo) + ", " + std::to_string(hi) +
           "]");
    }
    return static_cast<long long>(value);
  }

  bool Bool() const {
    bool value = false;
    if (node_.IsScalar()) {
      if (YAML::convert<bool>::decode(node_, value)) return value;
      if (node_.Scalar() == "0") return false;
      if (node_.Scalar() == "1") return true;
    }
    Fail("= " + Describe() + " is not a boolean (true or false)");
  }

  std::string Text() const {
    if (IsNull()) return "";
    if (!node_.IsScalar()) Fail("= " + Describe() + " must be a string");
    return node_.Scalar();
  }

  /// How the value reads in a message: its text, quoted unless it is a number.
  std::string Describe() const {
    if (IsNull()) return "null";
    if (node_.IsSequence()) return "a list of " + std::to_string(node_.size());
    if (node_.IsMap()) return "a map";
    double number = 0.0;
    if (YAML::convert<double>::decode(node_, number)) return node_.Scalar();
    return "'" + node_.Scalar() + "'";
  }

  void RequireMap() const {
    if (!node_.IsMap()) Fail("= " + Describe() + " must be a map");
  }

 private:
  std::string Join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  YAML::Node node_;
  std::string path_;
  const std::string* source_;
};

/// Parses a whole document; malformed YAML names the file, line and column.
YAML::Node ParseDocument(const std::string& text, const std::string& source, const char* expected) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    ThrowInvalid(source + ": malformed YAML at line " + std::to_string(e.mark.line + 1) + ", column " +
                 std::to_string(e.mark.column + 1) + ": " + e.msg);
  } catch (const YAML::Exception& e) {
    ThrowInvalid(source + ": malformed YAML: " + e.what());
  }
  if (!root.IsDefined() || root.IsNull()) ThrowInvalid(source + " is empty (expected a " + std::string(expected) + ")");
  if (!root.IsMap()) {
    ThrowInvalid(source + " is not a YAML map (expected a " + std::string(expected) + " with its field names as keys)");
  }
  return root;
}

/// The list at `holder.key`; absent or null = empty.
std::vector<Value> ListAt(const Value& holder, const std::string& key) {
  const std::optional<Value> list = holder.Find(key);
  return list ? list->Items() : std::vector<Value>{};
}

/// A Vector3 / Point: [x, y, z] or {x, y, z}.
Eigen::Vector3d ReadVector(const Value& value) {
  Eigen::Vector3d v;
  if (value.node().IsSequence()) {
    const std::vector<Value> items = value.Items();
    if (items.size() != 3) value.Fail("has " + std::to_string(items.size()) + " numbers, expected 3 (x, y, z)");
    for (int i = 0; i < 3; ++i) v[i] = items[i].Number();
    return v;
  }
  value.RequireMap();
  v.x() = value.Get("x").Number();
  v.y() = value.Get("y").Number();
  v.z() = value.Get("z").Number();
  return v;
}

/// A Quaternion, x y z w order: [x, y, z, w] or {x, y, z, w}; normalised; zero is an error.
Eigen::Quaterniond ReadQuaternion(const Value& value) {
  double x = 0.0, y = 0.0, z = 0.0, w = 0.0;
  if (value.node().IsSequence()) {
    const std::vector<Value> items = value.Items();
    if (items.size() != 4) value.Fail("has " + std::to_string(items.size()) + " numbers, expected 4 (x, y, z, w)");
    x = items[0].Number();
    y = items[1].Number();
    z = items[2].Number();
    w = items[3].Number();
  } else {
    value.RequireMap();
    x = value.Get("x").Number();
    y = value.Get("y").Number();
    z = value.Get("z").Number();
    w = value.Get("w").Number();
  }
  Eigen::Quaterniond q(w, x, y, z);  // Eigen's constructor takes w first
  const double norm = q.norm();
  if (!(norm > 1e-9)) {
    value.Fail("= (x " + FormatNumber(x) + ", y " + FormatNumber(y) + ", z " + FormatNumber(z) + ", w " +
               FormatNumber(w) + ") has norm 0: a rotation needs a non-zero quaternion (x, y, z, w)");
  }
  q.coeffs() /= norm;
  return q;
}

/// A Pose {position, orientation}; a missing position is the origin, a missing orientation identity.
Eigen::Isometry3d ReadPose(const Value& value) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  if (value.IsNull()) return pose;
  value.RequireMap();
  if (auto position = value.Find("position")) pose.translation() = ReadVector(*position);
  if (auto orientation = value.Find("orientation")) pose.linear() = ReadQuaternion(*orientation).toRotationMatrix();
  return pose;
}

/// A Transform {translation, rotation}.
Eigen::Isometry3d ReadTransform(const Value& value) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  value.RequireMap();
  if (auto translation = value.Find("translation")) pose.translation() = ReadVector(*translation);
  if (auto rotation = value.Find("rotation")) pose.linear() = ReadQuaternion(*rotation).toRotationMatrix();
  return pose;
}

/// A header's frame id ("world" when there is no header, as Robowflex writes it).
std::string FrameOf(const Value& holder) {
  auto header = holder.Find("header");
  if (!header) return "world";
  auto frame = header->Find("frame_id");
  return frame ? frame->Text() : "";
}

/// The frames a scene's objects may be given in: the base, and what fixed_frame_transforms add.
class Frames {
 public:
  Frames(const Value& scene, const RobotInfo& robot) : root_(robot.root_link) {
    for (const Value& t : ListAt(scene, "fixed_frame_transforms")) {
      const std::string child = t.Get("child_frame_id").Text();
      const std::optional<Value> transform = t.Find("transform");
      if (IsBase(child)) continue;  // the base is fixed by definition (e.g. base_link -> base_link)
      edges_[child] = {FrameOf(t), transform ? ReadTransform(*transform) : Eigen::Isometry3d::Identity()};
    }
  }

  bool IsBase(const std::string& frame) const {
    return frame.empty() || frame == "world" || frame == "/world" || frame == root_;
  }

  /// The pose in the base frame of the frame `holder` is given in (its header.frame_id, FrameOf);
  /// errors point at that frame_id (or at the holder when it has none).
  Eigen::Isometry3d Of(const Value& holder) const {
    const std::optional<Value> header = holder.Find("header");
    const std::optional<Value> frame_id = header ? header->Find("frame_id") : std::nullopt;
    return Resolve(FrameOf(holder), frame_id ? *frame_id : holder);
  }

  /// The pose of `frame` in the base frame; `where` is the header the frame came from.
  Eigen::Isometry3d Resolve(const std::string& frame, const Value& where) const {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    std::string current = frame;
    for (std::size_t steps = 0; !IsBase(current); ++steps) {
      const auto it = edges_.find(current);
      if (it == edges_.end() || steps > edges_.size()) {
        std::string others;
        for (const auto& [name, edge] : edges_) others += (others.empty() ? "'" : ", '") + name + "'";
        where.Fail("= '" + frame + "' is not a known frame" +
                   std::string(it == edges_.end() ? "" : " (fixed_frame_transforms form a cycle)") +
                   ": objects must be given in the robot's base frame ('" + root_ +
                   "', 'world', '/world' or '') or in a frame that fixed_frame_transforms lead to from it" +
                   (others.empty() ? std::string(" (there are none)") : " (" + others + ")"));
      }
      pose = it->second.transform * pose;
      current = it->second.parent;
    }
    return pose;
  }

 private:
  struct Edge {
    std::string parent;
    Eigen::Isometry3d transform;
  };
  std::string root_;
  std::map<std::string, Edge> edges_;
};

/// A robot state's joint positions by name (every name in the file, robot joint or not).
std::map<std::string, double> ReadJointState(const Value& state) {
  std::map<std::string, double> positions;
  auto joint_state = state.Find("joint_state");
  if (!joint_state) return positions;
  const std::vector<Value> name_items = ListAt(*joint_state, "name");
  const std::vector<Value> value_items = ListAt(*joint_state, "position");
  if (name_items.size() != value_items.size()) {
    joint_state->Fail("has " + std::to_string(name_items.size()) + " names and " + std::to_string(value_items.size()) +
                      " positions: they must match one to one");
  }
  for (std::size_t i = 0; i < name_items.size(); ++i) {
    const std::string name = name_items[i].Text();
    if (!positions.emplace(name, value_items[i].Number()).second) {
      name_items[i].Fail("= '" + name + "' appears twice in " + joint_state->path() + ".name");
    }
  }
  return positions;
}

/// The allowed collision matrix as MoveIt reads it.
class AllowedCollisions {
 public:
  explicit AllowedCollisions(const std::optional<Value>& acm) {
    if (!acm) return;
    const std::vector<Value> names = ListAt(*acm, "entry_names");
    const std::vector<Value> rows = ListAt(*acm, "entry_values");
    if (rows.size() != names.size()) {
      acm->Fail("has " + std::to_string(names.size()) + " entry_names and " + std::to_string(rows.size()) +
                " entry_values: there must be one row per name");
    }
    for (std::size_t i = 0; i < names.size(); ++i) {
      const std::string name = names[i].Text();
      if (!index_.emplace(name, static_cast<int>(i)).second) names[i].Fail("= '" + name + "' appears twice");
    }
    values_.assign(names.size(), std::vector<char>(names.size(), 0));
    for (std::size_t i = 0; i < rows.size(); ++i) {
      // A row is {enabled: [...]} (the message) or the list itself (Robowflex).
      const Value row = rows[i].node().IsMap() ? rows[i].Get("enabled") : rows[i];
      const std::vector<Value> cells = row.Items();
      if (cells.size() != names.size()) {
        row.Fail("has " + std::to_string(cells.size()) + " values, expected " + std::to_string(names.size()) +
                 " (one per entry name)");
      }
      for (std::size_t j = 0; j < cells.size(); ++j) values_[i][j] = cells[j].Bool() ? 1 : 0;
    }
    const std::vector<Value> default_names = ListAt(*acm, "default_entry_names");
    const std::vector<Value> default_values = ListAt(*acm, "default_entry_values");
    if (default_names.size() != default_values.size()) {
      acm->Fail("has " + std::to_string(default_names.size()) + " default_entry_names and " +
                std::to_string(default_values.size()) + " default_entry_values: they must match one to one");
    }
    for (std::size_t i = 0; i < default_names.size(); ++i) {
      defaults_[default_names[i].Text()] = default_values[i].Bool();
    }
  }

  /// MoveIt's rule: the pair's entry; else the names' defaults (one decides; two must both allow).
  bool Allowed(const std::string& a, const std::string& b) const {
    const auto ia = index_.find(a);
    const auto ib = index_.find(b);
    if (ia != index_.end() && ib != index_.end()) {
      // MoveIt reads the upper triangle of the matrix.
      const int i = std::min(ia->second, ib->second);
      const int j = std::max(ia->second, ib->second);
      return values_[i][j] != 0;
    }
    const auto da = defaults_.find(a);
    const auto db = defaults_.find(b);
    if (da == defaults_.end() && db == defaults_.end()) return false;
    if (da == defaults_.end()) return db->second;
    if (db == defaults_.end()) return da->second;
    return da->second && db->second;
  }

  bool empty() const { return index_.empty() && defaults_.empty(); }

 private:
  std::map<std::string, int> index_;
  std::vector<std::vector<char>> values_;
  std::map<std::string, bool> defaults_;
};

/// One MoveIt collision object after conversion: its id and the names of its Chasles shapes.
struct ObjectShapes {
  std::string id;
  std::vector<std::string> shapes;
};

const char* PrimitiveName(long long type) {
  switch (type) {
    case 1:
      return "BOX";
    case 2:
      return "SPHERE";
    case 3:
      return "CYLINDER";
    case 4:
      return "CONE";
    case 5:
      return "PRISM";
    default:
      return "unknown";
  }
}

/// shape_msgs/SolidPrimitive type: a number or its name (case-insensitive).
long long ReadPrimitiveType(const Value& type) {
  std::string text = type.Text();
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  if (lower == "box") return 1;
  if (lower == "sphere") return 2;
  if (lower == "cylinder") return 3;
  if (lower == "cone") return 4;
  if (lower == "prism") return 5;
  double number = 0.0;
  if (!YAML::convert<double>::decode(type.node(), number)) {
    type.Fail("= '" + text + "' is not a primitive type (BOX = 1, SPHERE = 2, CYLINDER = 3, or their names)");
  }
  return type.Integer(0, 255);
}

/// Adds the primitive to `scene` (a v1::Scene, or a v1::AttachedObject: the same shape lists).
template <typename Shapes>
void AddPrimitive(const Value& primitive, const Eigen::Isometry3d& pose, const std::string& name, Shapes* scene) {
  primitive.RequireMap();
  const Value type_value = primitive.Get("type");
  const long long type = ReadPrimitiveType(type_value);
  if (type < 1 || type > 3) {
    type_value.Fail("= " + std::to_string(type) + " (" + PrimitiveName(type) +
                    ") is not supported (BOX, SPHERE, CYLINDER and meshes are)");
  }
  const Value dims_value = primitive.Get("dimensions");
  const std::vector<Value> items = dims_value.Items();
  const std::size_t expected = type == 1 ? 3 : type == 2 ? 1 : 2;
  const char* layout = type == 1 ? "[x, y, z] full extents" : type == 2 ? "[radius]" : "[height, radius]";
  if (items.size() != expected) {
    dims_value.Fail("has " + std::to_string(items.size()) + " values: a " + PrimitiveName(type) + " has " +
                    std::to_string(expected) + " (" + layout + ")");
  }
  std::vector<double> dims;
  for (const Value& item : items) {
    const double d = item.Number();
    if (!(d > 0.0)) item.Fail("= " + FormatNumber(d) + " must be > 0 (" + PrimitiveName(type) + " " + layout + ")");
    dims.push_back(d);
  }
  if (type == 1) {
    v1::Box* box = scene->add_boxes();
    box->set_name(name);
    box->mutable_size()->set_x(dims[0]);
    box->mutable_size()->set_y(dims[1]);
    box->mutable_size()->set_z(dims[2]);
    PoseToProto(pose, box->mutable_pose());
  } else if (type == 2) {
    v1::Sphere* sphere = scene->add_spheres();
    sphere->set_name(name);
    sphere->set_radius(dims[0]);
    PoseToProto(pose, sphere->mutable_pose());
  } else {
    v1::Cylinder* cylinder = scene->add_cylinders();  // MoveIt's cylinder axis is z too
    cylinder->set_name(name);
    cylinder->set_length(dims[0]);
    cylinder->set_radius(dims[1]);
    PoseToProto(pose, cylinder->mutable_pose());
  }
}

/// shape_msgs/Mesh -> OBJ text.
void AddMesh(const Value& mesh, const Eigen::Isometry3d& pose, const std::string& name, v1::Scene* scene) {
  mesh.RequireMap();
  if (auto resource = mesh.Find("resource")) {
    resource->Fail("= '" + resource->Text() +
                   "': mesh resources are not supported (give the mesh inline as triangles and vertices)");
  }
  const Value vertices_value = mesh.Get("vertices");
  const Value triangles_value = mesh.Get("triangles");
  const std::vector<Value> vertices = vertices_value.Items();
  const std::vector<Value> triangles = triangles_value.Items();
  if (vertices.empty()) vertices_value.Fail("is empty: a mesh needs vertices");
  if (triangles.empty()) triangles_value.Fail("is empty: a mesh needs triangles");
  std::ostringstream obj;
  obj << "# " << name << " (moveit shape_msgs/Mesh)\n";
  for (const Value& vertex : vertices) {
    const Eigen::Vector3d v = ReadVector(vertex);
    obj << "v " << FormatNumber(v.x()) << ' ' << FormatNumber(v.y()) << ' ' << FormatNumber(v.z()) << '\n';
  }
  const long long last = static_cast<long long>(vertices.size()) - 1;
  for (const Value& triangle : triangles) {
    // {vertex_indices: [a, b, c]} (the message) or [a, b, c] (Robowflex).
    const Value indices = triangle.node().IsMap() ? triangle.Get("vertex_indices") : triangle;
    const std::vector<Value> corners = indices.Items();
    if (corners.size() != 3) indices.Fail("has " + std::to_string(corners.size()) + " vertex indices, expected 3");
    obj << 'f';
    for (const Value& corner : corners) obj << ' ' << corner.Integer(0, last) + 1;  // OBJ counts from 1
    obj << '\n';
  }
  v1::Mesh* out = scene->add_meshes();
  out->set_name(name);
  out->set_data(obj.str());
  PoseToProto(pose, out->mutable_pose());
}

void RejectNonEmpty(const Value& holder, const std::string& key, const std::string& rule) {
  if (auto list = holder.Find(key); list && list->Count() > 0) {
    list->Fail("has " + std::to_string(list->Count()) + " entries: " + rule);
  }
}

/// Operation ADD: 0, "add" or absent. Robowflex writes names, moveit_msgs numbers.
void RequireAdd(const Value& object) {
  auto op = object.Find("operation");
  if (!op) return;
  static const char* kNames[] = {"ADD", "REMOVE", "APPEND", "MOVE"};
  std::string text = op->Text();
  std::string upper = text;
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return std::toupper(c); });
  for (int i = 0; i < 4; ++i) {
    if (upper == kNames[i]) {
      if (i == 0) return;
      op->Fail("= '" + text + "' (" + kNames[i] +
               ") is not supported: a scene is read as a whole, so every object "
               "must be ADD (0)");
    }
  }
  const long long code = op->Integer(0, 255);
  if (code == 0) return;
  op->Fail("= " + std::to_string(code) + " (" + (code < 4 ? kNames[code] : "unknown") +
           ") is not supported: a scene is read as a whole, so every object must be ADD (0)");
}

/// A collision object's `poses_key` list, one pose per shape of its `count` `shapes_key`.
std::vector<Value> PosesFor(const Value& object, const char* shapes_key, const char* poses_key, std::size_t count) {
  std::vector<Value> poses = ListAt(object, poses_key);
  if (count > 0 && poses.size() != count) {
    ThrowInvalid(object.source() + ": " + object.path() + "." + poses_key + " has " + std::to_string(poses.size()) +
                 " poses for " + std::to_string(count) + " " + shapes_key + ": there must be one per shape");
  }
  return poses;
}

/// A scene's conversion and the robot state it carries.
struct ParsedScene {
  v1::Scene scene;
  std::map<std::string, double> joint_positions;
  std::optional<Frames> frames;        ///< the scene's frames (fixed_frame_transforms)
  std::vector<Value> attached;         ///< robot_state.attached_collision_objects
};

ParsedScene ParseScene(const std::string& yaml, const RobotInfo& robot, const std::string& source) {
  const YAML::Node root_node = ParseDocument(yaml, source, "moveit_msgs/PlanningScene");
  const Value root(root_node, "", &source);
  ParsedScene parsed;
  v1::Scene& scene = parsed.scene;

  if (auto state = root.Find("robot_state")) {
    parsed.joint_positions = ReadJointState(*state);
    parsed.attached = ListAt(*state, "attached_collision_objects");
  }

  const std::set<std::string> links(robot.link_names.begin(), robot.link_names.end());
  parsed.frames.emplace(root, robot);
  const Frames& frames = *parsed.frames;
  std::vector<ObjectShapes> objects;
  std::map<std::string, std::string> object_paths;  // id -> path, for duplicates
  std::set<std::string> shape_names;
  if (auto world = root.Find("world")) {
    // world.octomap (octomap_msgs/OctomapWithPose): its tree as an OctoMap of the scene, at its
    // frame ∘ origin.
    if (auto octomap = world->Find("octomap")) {
      const std::optional<Value> map = octomap->Find("octomap");
      const std::optional<Value> data = map ? map->Find("data") : std::nullopt;
      if (data && !data->node().IsSequence() && !data->Text().empty()) {
        data->Fail("is a string: write octomap_msgs/Octomap data as a list of int8 values");
      }
      if (data && data->Count() > 0) {
        std::string bytes;
        bytes.reserve(data->Count());
        for (const Value& item : data->Items()) bytes.push_back(static_cast<char>(item.Integer(-128, 255)));
        const std::optional<Value> binary = map->Find("binary");
        const std::optional<Value> id = map->Find("id");
        const std::string file =
            OctoMapFileFromMessage(binary ? binary->Bool() : false, id ? id->Text() : "OcTree",
                                   map->Get("resolution").Number(), bytes, source + ": " + map->path());
        Eigen::Isometry3d pose = frames.Of(*octomap);
        if (const std::optional<Value> origin = octomap->Find("origin")) pose = pose * ReadPose(*origin);
        v1::OctoMap* added = scene.add_octomaps();
        added->set_name("octomap");
        added->set_data(file);
        PoseToProto(pose, added->mutable_pose());
      }
    }
    for (const Value& object : ListAt(*world, "collision_objects")) {
      object.RequireMap();
      const Value id_value = object.Get("id");
      const std::string id = id_value.Text();
      if (id.empty()) id_value.Fail("is empty: every object needs an id");
      if (links.count(id) != 0) id_value.Fail("= '" + id + "' is a link of the robot: object ids must differ");
      if (const auto [it, inserted] = object_paths.emplace(id, id_value.path()); !inserted) {
        id_value.Fail("= '" + id + "' repeats " + it->second);
      }
      RequireAdd(object);
      RejectNonEmpty(object, "planes", "planes are not supported (use a thin BOX)");
      const Eigen::Isometry3d frame = frames.Of(object);
      const std::optional<Value> pose = object.Find("pose");
      const Eigen::Isometry3d object_pose = pose ? frame * ReadPose(*pose) : frame;

      const std::vector<Value> primitives = ListAt(object, "primitives");
      const std::vector<Value> meshes = ListAt(object, "meshes");
      const std::size_t total = primitives.size() + meshes.size();
      if (total == 0) object.Fail("(id '" + id + "') has no primitives and no meshes: it needs a shape");
      const std::vector<Value> primitive_poses = PosesFor(object, "primitives", "primitive_poses", primitives.size());
      const std::vector<Value> mesh_poses = PosesFor(object, "meshes", "mesh_poses", meshes.size());

      ObjectShapes shapes{id, {}};
      for (std::size_t k = 0; k < total; ++k) {
        const std::string name = total == 1 ? id : id + "/" + std::to_string(k);
        if (!shape_names.insert(name).second) {
          object.Fail("(id '" + id + "') makes a shape named '" + name + "', which another object's shape has already");
        }
        if (k < primitives.size()) {
          AddPrimitive(primitives[k], object_pose * ReadPose(primitive_poses[k]), name, &scene);
        } else {
          const std::size_t m = k - primitives.size();
          AddMesh(meshes[m], object_pose * ReadPose(mesh_poses[m]), name, &scene);
        }
        shapes.shapes.push_back(name);
      }
      objects.push_back(std::move(shapes));
    }
  }
  // An object id that equals another object's shape name ("a/0") would be ambiguous in the ACM.
  for (const ObjectShapes& object : objects) {
    if (object.shapes.size() > 1 && shape_names.count(object.id) != 0) {
      ThrowInvalid(source + ": " + object_paths[object.id] + " = '" + object.id +
                   "' is also the name of another object's shape");
    }
  }

  const AllowedCollisions acm(root.Find("allowed_collision_matrix"));
  if (!acm.empty()) {
    for (const ObjectShapes& object : objects) {
      for (const std::string& link : robot.link_names) {
        if (!acm.Allowed(link, object.id)) continue;
        for (const std::string& shape : object.shapes) {
          v1::LinkPair* pair = scene.add_allowed_collisions();
          pair->set_link1(link);
          pair->set_link2(shape);
        }
      }
    }
    for (std::size_t i = 0; i < robot.link_names.size(); ++i) {
      for (std::size_t j = i + 1; j < robot.link_names.size(); ++j) {
        const std::string& a = robot.link_names[i];
        const std::string& b = robot.link_names[j];
        if (!acm.Allowed(a, b)) continue;
        const auto key = a < b ? std::make_pair(a, b) : std::make_pair(b, a);
        if (std::binary_search(robot.allowed_link_pairs.begin(), robot.allowed_link_pairs.end(), key)) continue;
        v1::LinkPair* pair = scene.add_allowed_collisions();
        pair->set_link1(a);
        pair->set_link2(b);
      }
    }
  }
  return parsed;
}

RobotInfo InfoFromModel(v1::RobotModel model) {
  const std::shared_ptr<const RobotModel> robot = RobotFromProto(model, "robot");
  RobotInfo info;
  info.model = std::move(model);
  info.joint_names = robot->dof_names();
  for (const Link& link : robot->links()) info.link_names.push_back(link.name);
  info.root_link = robot->links()[robot->root_link()].name;
  const AllowedCollisionMatrix& acm = robot->allowed_collisions();
  for (int i = 0; i < robot->num_links(); ++i) {
    for (int j = i + 1; j < robot->num_links(); ++j) {
      if (!acm.IsAllowed(i, j)) continue;
      const std::string& a = info.link_names[i];
      const std::string& b = info.link_names[j];
      info.allowed_link_pairs.push_back(a < b ? std::make_pair(a, b) : std::make_pair(b, a));
    }
  }
  std::sort(info.allowed_link_pairs.begin(), info.allowed_link_pairs.end());
  return info;
}

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowInvalid("cannot read '" + path.string() + "'");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

/// The start: the scene's robot state, overlaid by the request's start_state, in the robot's
/// joint order.
void ReadStart(const Value& root, const ParsedScene& scene, const RobotInfo& robot, const std::string& scene_source,
               const std::string& request_source, v1::JointState* out) {
  std::map<std::string, double> start_positions;
  if (auto start_state = root.Find("start_state")) start_positions = ReadJointState(*start_state);
  for (const std::string& joint : robot.joint_names) {
    std::map<std::string, double>::const_iterator it = start_positions.find(joint);
    if (it == start_positions.end()) it = scene.joint_positions.find(joint);
    if (it == scene.joint_positions.end()) {
      ThrowInvalid(request_source + ": start_state.joint_state has no position for joint '" + joint + "' (nor has " +
                   scene_source + ": robot_state.joint_state); the robot's joints are " + JoinNames(robot.joint_names));
    }
    out->add_positions(it->second);
  }
}

/// A constraint's link_name, which must be a link of the robot.
std::string LinkName(const Value& constraint, const RobotInfo& robot) {
  const Value link_value = constraint.Get("link_name");
  const std::string link = link_value.Text();
  if (std::find(robot.link_names.begin(), robot.link_names.end(), link) == robot.link_names.end()) {
    link_value.Fail("= '" + link + "' is not a link of the robot (" + JoinNames(robot.link_names) + ")");
  }
  return link;
}

/// The region of a moveit_msgs/PositionConstraint: one primitive with its pose (meshes refused).
/// `what` names the use in messages ("a goal region", "a path constraint's region"); dimensions
/// must be > 0, or >= 0 with `allow_zero` (a box that is a plane).
struct PositionRegion {
  Value type_value;
  long long type = 0;
  std::vector<double> dims;
  Eigen::Isometry3d pose;  ///< in the constraint's header frame
};
PositionRegion ReadPositionRegion(const Value& constraint, const std::string& what, const char* mesh_message,
                                  bool allow_zero) {
  const Value region = constraint.Get("constraint_region");
  RejectNonEmpty(region, "meshes", mesh_message);
  const std::vector<Value> primitives = ListAt(region, "primitives");
  const std::vector<Value> poses = ListAt(region, "primitive_poses");
  if (primitives.size() != 1 || poses.size() != 1) {
    region.Fail("has " + std::to_string(primitives.size()) + " primitives and " + std::to_string(poses.size()) +
                " poses: " + what + " here is one primitive with its pose");
  }
  PositionRegion out{primitives[0].Get("type"), 0, {}, ReadPose(poses[0])};
  out.type = ReadPrimitiveType(out.type_value);
  for (const Value& item : primitives[0].Get("dimensions").Items()) {
    const double d = item.Number();
    if (!(allow_zero ? d >= 0.0 : d > 0.0)) item.Fail("= " + FormatNumber(d) + (allow_zero ? " must be >= 0" : " must be > 0"));
    out.dims.push_back(d);
  }
  return out;
}

/// One position constraint and one orientation constraint on the same link -> a PoseGoal,
/// conservatively: the position tolerance is the radius of the largest ball about the region's
/// centre inside it (a SPHERE's radius, half a BOX's least extent, a CYLINDER's radius or half
/// height; at most 0.1 m), the orientation tolerance the least of the three axis tolerances (at
/// most 0.5 rad), so every pose within them is within MoveIt's region (for the rotation-vector
/// form of its axis tolerances exactly, to first order for Euler angles).
void ReadPoseGoal(const Value& goal, const Frames& frames, const RobotInfo& robot, v1::PoseGoal* out) {
  const std::vector<Value> positions = ListAt(goal, "position_constraints");
  const std::vector<Value> orientations = ListAt(goal, "orientation_constraints");
  if (positions.size() != 1 || orientations.size() != 1) {
    goal.Fail("has " + std::to_string(positions.size()) + " position and " + std::to_string(orientations.size()) +
              " orientation constraints: a pose goal needs exactly one of each (on the same link)");
  }
  const Value& position = positions[0];
  const Value& orientation = orientations[0];
  const std::string link = LinkName(position, robot);
  const Value other = orientation.Get("link_name");
  if (other.Text() != link) other.Fail("= '" + other.Text() + "' differs from the position constraint's '" + link + "'");
  if (auto offset = position.Find("target_point_offset")) {
    if (!ReadVector(*offset).isZero()) offset->Fail("is not supported (a point offset from the link frame): give 0");
  }
  const PositionRegion region =
      ReadPositionRegion(position, "a goal region", "mesh regions are not supported (a SPHERE, BOX or CYLINDER is)", false);
  const Value& type_value = region.type_value;
  const long long type = region.type;
  const std::vector<double>& dims = region.dims;
  double radius = 0.0;
  if (type == 2 && dims.size() == 1) {
    radius = dims[0];
  } else if (type == 1 && dims.size() == 3) {
    radius = 0.5 * std::min({dims[0], dims[1], dims[2]});
  } else if (type == 3 && dims.size() == 2) {
    radius = std::min(dims[1], 0.5 * dims[0]);
  } else {
    type_value.Fail("= " + std::to_string(type) + " (" + PrimitiveName(type) +
                    ") with these dimensions is not a goal region here (a SPHERE [r], BOX [x, y, z] or CYLINDER "
                    "[height, radius] is)");
  }
  double angle = std::numeric_limits<double>::infinity();
  for (const char* key : {"absolute_x_axis_tolerance", "absolute_y_axis_tolerance", "absolute_z_axis_tolerance"}) {
    const Value value = orientation.Get(key);
    const double t = value.Number();
    if (!(t > 0.0)) value.Fail("= " + FormatNumber(t) + " must be > 0");
    angle = std::min(angle, t);
  }
  const Eigen::Vector3d centre = frames.Of(position) * region.pose.translation();
  const Eigen::Matrix3d rotation = frames.Of(orientation).linear() * ReadQuaternion(orientation.Get("orientation")).toRotationMatrix();
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.translation() = centre;
  target.linear() = rotation;
  out->set_link(link);
  PoseToProto(target, out->mutable_pose());
  out->set_position_tolerance(std::min(radius, 0.1));
  out->set_orientation_tolerance(std::min(angle, 0.5));
}

void RejectPathConstraints(const Value& root, const char* why) {
  if (auto path = root.Find("path_constraints")) {
    for (const char* key :
         {"joint_constraints", "position_constraints", "orientation_constraints", "visibility_constraints"}) {
      RejectNonEmpty(*path, key, why);
    }
  }
}

/// moveit_msgs/Constraints path_constraints -> PathConstraints: each orientation constraint as
/// it is (its frame resolved to the base; tolerances above π, which no angle exceeds, become π);
/// each position constraint whose region is one BOX as a box (the target point offset is the
/// point on the link). Joint and visibility constraints, and other regions, are refused by name.
void ReadPathConstraints(const Value& root, const Frames& frames, const RobotInfo& robot, v1::PathConstraints* out) {
  const std::optional<Value> path = root.Find("path_constraints");
  if (!path) return;
  RejectNonEmpty(*path, "joint_constraints", "joint path constraints are not supported (orientation and position ones are)");
  RejectNonEmpty(*path, "visibility_constraints", "visibility constraints are not supported");
  for (const Value& c : ListAt(*path, "orientation_constraints")) {
    v1::OrientationConstraint* o = out->add_orientation();
    o->set_link(LinkName(c, robot));
    const Eigen::Quaterniond q(frames.Of(c).linear() * ReadQuaternion(c.Get("orientation")).toRotationMatrix());
    o->mutable_orientation()->set_x(q.x());
    o->mutable_orientation()->set_y(q.y());
    o->mutable_orientation()->set_z(q.z());
    o->mutable_orientation()->set_w(q.w());
    const auto tolerance = [&c](const char* key) {
      const Value value = c.Get(key);
      const double t = value.Number();
      if (!(t > 0.0)) value.Fail("= " + FormatNumber(t) + " must be > 0");
      return std::min(t, kPi);
    };
    o->mutable_tolerance()->set_x(tolerance("absolute_x_axis_tolerance"));
    o->mutable_tolerance()->set_y(tolerance("absolute_y_axis_tolerance"));
    o->mutable_tolerance()->set_z(tolerance("absolute_z_axis_tolerance"));
    long long parameterization = 0;  // moveit_msgs: XYZ_EULER_ANGLES = 0, ROTATION_VECTOR = 1
    if (auto p = c.Find("parameterization")) {
      parameterization = static_cast<long long>(p->Number());
      if (parameterization != 0 && parameterization != 1) {
        p->Fail("= " + std::to_string(parameterization) + " must be 0 (XYZ_EULER_ANGLES) or 1 (ROTATION_VECTOR)");
      }
    }
    o->set_parameterization(parameterization == 1 ? v1::OrientationConstraint::ROTATION_VECTOR
                                                  : v1::OrientationConstraint::XYZ_EULER_ANGLES);
    if (parameterization == 0 && o->tolerance().y() >= kPi / 2) {
      c.Get("absolute_y_axis_tolerance")
          .Fail("= " + FormatNumber(o->tolerance().y()) +
                " is not supported with XYZ_EULER_ANGLES (at |y| = π/2 the x and z angles are undefined): give less "
                "than π/2, or parameterization 1 (ROTATION_VECTOR)");
    }
  }
  for (const Value& c : ListAt(*path, "position_constraints")) {
    v1::PositionConstraint* p = out->add_position();
    p->set_link(LinkName(c, robot));
    if (auto offset = c.Find("target_point_offset")) {
      const Eigen::Vector3d v = ReadVector(*offset);
      p->mutable_point()->set_x(v.x());
      p->mutable_point()->set_y(v.y());
      p->mutable_point()->set_z(v.z());
    }
    const PositionRegion region = ReadPositionRegion(c, "a path constraint's region",
                                                     "mesh regions are not supported in path constraints (a BOX is)", true);
    const Value& type_value = region.type_value;
    const long long type = region.type;
    const std::vector<double>& dims = region.dims;
    if (type != 1 || dims.size() != 3) {
      type_value.Fail("= " + std::to_string(type) + " (" + PrimitiveName(type) +
                      ") is not a path constraint region here (a BOX [x, y, z] is)");
    }
    PoseToProto(frames.Of(c) * region.pose, p->mutable_region());
    p->mutable_half_extents()->set_x(0.5 * dims[0]);
    p->mutable_half_extents()->set_y(0.5 * dims[1]);
    p->mutable_half_extents()->set_z(0.5 * dims[2]);
  }
}

/// moveit_msgs/AttachedCollisionObject entries -> AttachedObjects (shapes in the link's frame):
/// the scene's robot_state ones, then the request's start_state ones (an id given again replaces
/// the scene's). An object given in a frame other than its link's is placed where `start` puts
/// that frame (a robot link by forward kinematics, the base or a scene frame as scene objects
/// are). Touch links the robot lacks (MoveIt's finger links) are dropped.
template <typename Request>
void ReadAttached(const ParsedScene& scene, const std::optional<Value>& start_state, const RobotInfo& robot,
                  Request* request) {
  std::vector<Value> items = scene.attached;
  if (start_state) {
    const std::vector<Value> more = ListAt(*start_state, "attached_collision_objects");
    items.insert(items.end(), more.begin(), more.end());
  }
  if (items.empty()) return;
  const std::shared_ptr<const RobotModel> model = RobotFromProto(robot.model, "robot");
  Eigen::VectorXd q(static_cast<Eigen::Index>(request->start().positions_size()));
  for (int i = 0; i < request->start().positions_size(); ++i) q[i] = request->start().positions(i);
  std::vector<Eigen::Isometry3d> poses;
  model->ForwardKinematics(q, &poses);
  const std::set<std::string> links(robot.link_names.begin(), robot.link_names.end());
  std::map<std::string, int> index;  // id -> its entry in request->attached_objects
  for (const Value& item : items) {
    item.RequireMap();
    const Value link_value = item.Get("link_name");
    const std::string link = link_value.Text();
    if (links.count(link) == 0) link_value.Fail("= '" + link + "' is not a link of the robot (" + JoinNames(robot.link_names) + ")");
    const Value object = item.Get("object");
    object.RequireMap();
    const Value id_value = object.Get("id");
    const std::string id = id_value.Text();
    if (id.empty()) id_value.Fail("is empty: every attached object needs an id");
    if (links.count(id) != 0) id_value.Fail("= '" + id + "' is a link of the robot: object ids must differ");
    RequireAdd(object);
    RejectNonEmpty(object, "meshes", "meshes of attached objects are not supported (BOX, SPHERE and CYLINDER are)");
    RejectNonEmpty(object, "planes", "planes are not supported (use a thin BOX)");
    // The object's frame in the link's frame.
    const Eigen::Isometry3d& link_pose = poses[static_cast<std::size_t>(model->FindLink(link))];
    const std::string frame = FrameOf(object);
    Eigen::Isometry3d in_link = Eigen::Isometry3d::Identity();
    if (frame != link) {
      const int frame_link = model->FindLink(frame);
      const Eigen::Isometry3d frame_pose = frame_link >= 0 && !scene.frames->IsBase(frame)
                                               ? poses[static_cast<std::size_t>(frame_link)]
                                               : scene.frames->Of(object);
      in_link = link_pose.inverse() * frame_pose;
    }
    if (const std::optional<Value> pose = object.Find("pose")) in_link = in_link * ReadPose(*pose);
    const std::vector<Value> primitives = ListAt(object, "primitives");
    if (primitives.empty()) object.Fail("(id '" + id + "') has no primitives: it needs a shape");
    const std::vector<Value> primitive_poses = PosesFor(object, "primitives", "primitive_poses", primitives.size());
    v1::AttachedObject converted;
    converted.set_name(id);
    converted.set_link(link);
    for (std::size_t k = 0; k < primitives.size(); ++k) {
      AddPrimitive(primitives[k], in_link * ReadPose(primitive_poses[k]), id, &converted);
    }
    for (const Value& touch : ListAt(item, "touch_links")) {
      const std::string name = touch.Text();
      if (links.count(name) != 0 && name != link) converted.add_touch_links(name);
    }
    const auto [at, inserted] = index.emplace(id, request->attached_objects_size());
    if (inserted) {
      *request->add_attached_objects() = std::move(converted);
    } else {
      *request->mutable_attached_objects(at->second) = std::move(converted);
    }
  }
}

}  // namespace

bool IsCartesianPathRequest(const std::string& request_yaml) {
  try {
    const YAML::Node root = YAML::Load(request_yaml);
    return root.IsMap() && root["waypoints"].IsDefined();
  } catch (const YAML::Exception&) {
    return false;  // the importer names the error
  }
}

v1::CartesianPathRequest ImportCartesianPathRequest(const std::string& scene_yaml, const std::string& request_yaml,
                                                    const RobotInfo& robot, const std::string& scene_source,
                                                    const std::string& request_source) {
  ParsedScene scene = ParseScene(scene_yaml, robot, scene_source);
  const Frames& frames = *scene.frames;
  const YAML::Node root_node = ParseDocument(request_yaml, request_source, "moveit_msgs/GetCartesianPath request");
  const Value root(root_node, "", &request_source);
  v1::CartesianPathRequest request;
  ReadStart(root, scene, robot, scene_source, request_source, request.mutable_start());
  ReadAttached(scene, root.Find("start_state"), robot, &request);
  if (auto link = root.Find("link_name")) {
    const std::string name = link->Text();
    if (std::find(robot.link_names.begin(), robot.link_names.end(), name) == robot.link_names.end()) {
      link->Fail("= '" + name + "' is not a link of the robot (" + JoinNames(robot.link_names) + ")");
    }
    request.set_link(name);
  }
  // The waypoints' frame: header.frame_id (the base for "" or absent).
  const Eigen::Isometry3d frame = frames.Of(root);
  const Value waypoints = root.Get("waypoints");
  const std::vector<Value> poses = waypoints.Items();
  if (poses.empty()) waypoints.Fail("is empty: a Cartesian path needs at least one waypoint");
  for (const Value& pose : poses) PoseToProto(frame * ReadPose(pose), request.add_waypoints());
  if (auto step = root.Find("max_step")) {
    const double value = step->Number();
    if (!(value > 0.0)) step->Fail("= " + FormatNumber(value) + " must be > 0 [m]");
    request.set_max_step(value);
  }
  if (auto jump = root.Find("jump_threshold")) {
    const double value = jump->Number();
    if (!(value == 0.0 || value >= 1.0)) {
      jump->Fail("= " + FormatNumber(value) + " must be 0 (off) or >= 1 (a multiple of the mean step)");
    }
    request.set_jump_threshold(value);
  }
  if (auto revolute = root.Find("revolute_jump_threshold")) {
    const double value = revolute->Number();
    if (value < 0.0) revolute->Fail("= " + FormatNumber(value) + " must be >= 0 (0 = off)");
    if (value > 0.0) request.set_max_joint_jump(value);
  }
  if (auto prismatic = root.Find("prismatic_jump_threshold")) {
    if (prismatic->Number() != 0.0) {
      prismatic->Fail("is not supported: Chasles has one absolute jump limit for every joint "
                      "(revolute_jump_threshold becomes max_joint_jump)");
    }
  }
  // moveit_msgs leaves avoid_collisions false when absent; a Cartesian path here is checked
  // unless the file says false.
  if (auto avoid = root.Find("avoid_collisions")) request.set_ignore_collisions(!avoid->Bool());
  RejectPathConstraints(root, "path constraints are not supported on Cartesian paths (the link follows its lines)");
  if (auto speed = root.Find("max_cartesian_speed")) {
    if (speed->Number() != 0.0) speed->Fail("is not supported (a Cartesian speed limit on a link)");
  }
  *request.mutable_scene() = std::move(scene.scene);
  return request;
}

RobotInfo DefaultRobot() { return RobotFromUrdf(std::string(kDefaultRobotUrdf), std::string(kDefaultRobotSrdf)); }

RobotInfo RobotFromUrdf(const std::string& urdf, const std::string& srdf) {
  v1::RobotModel model;
  model.mutable_urdf()->set_urdf(urdf);
  model.mutable_urdf()->set_srdf(srdf);
  return InfoFromModel(std::move(model));
}

v1::Scene ImportPlanningScene(const std::string& yaml, const RobotInfo& robot, const std::string& source) {
  ParsedScene parsed = ParseScene(yaml, robot, source);
  if (!parsed.attached.empty()) {
    ThrowInvalid(source + ": robot_state.attached_collision_objects has " + std::to_string(parsed.attached.size()) +
                 " objects: a scene alone cannot carry them (they belong to the robot); import the scene with its "
                 "request, which attaches them (attached_objects)");
  }
  return std::move(parsed.scene);
}

v1::PlanRequest ImportMotionPlanRequest(const std::string& scene_yaml, const std::string& request_yaml,
                                        const RobotInfo& robot, const std::string& scene_source,
                                        const std::string& request_source) {
  ParsedScene scene = ParseScene(scene_yaml, robot, scene_source);
  const YAML::Node root_node = ParseDocument(request_yaml, request_source, "moveit_msgs/MotionPlanRequest");
  const Value root(root_node, "", &request_source);

  v1::PlanRequest request;
  ReadStart(root, scene, robot, scene_source, request_source, request.mutable_start());
  ReadAttached(scene, root.Find("start_state"), robot, &request);

  // Goal: one set of joint constraints.
  const Value goals_value = root.Get("goal_constraints");
  const std::vector<Value> goals = goals_value.Items();
  if (goals.empty()) goals_value.Fail("is empty: a joint goal is required");
  if (goals.size() > 1) {
    goals_value.Fail("has " + std::to_string(goals.size()) +
                     " entries: only one goal is supported (MoveIt accepts any of them; keep the one to plan to)");
  }
  const Value& goal = goals[0];
  goal.RequireMap();
  RejectNonEmpty(goal, "visibility_constraints",
                 "visibility constraints are not supported (joint constraints, or one position and one "
                 "orientation constraint, are)");
  // A goal region for a link (one position and one orientation constraint) is a pose goal.
  const bool pose_goal =
      !ListAt(goal, "position_constraints").empty() || !ListAt(goal, "orientation_constraints").empty();
  if (pose_goal) {
    if (!ListAt(goal, "joint_constraints").empty()) {
      goal.Fail("mixes joint constraints with position/orientation constraints: give one kind");
    }
    ReadPoseGoal(goal, *scene.frames, robot, request.mutable_pose_goal());
  }
  if (!pose_goal) {
    std::map<std::string, std::pair<double, double>> targets;  // joint -> (position, tolerance)
    const std::vector<Value> constraints = ListAt(goal, "joint_constraints");
    const std::set<std::string> robot_joints(robot.joint_names.begin(), robot.joint_names.end());
    for (const Value& constraint : constraints) {
      constraint.RequireMap();
      const Value name_value = constraint.Get("joint_name");
      const std::string name = name_value.Text();
      const double position = constraint.Get("position").Number();
      double tolerance = std::numeric_limits<double>::infinity();
      for (const char* key : {"tolerance_above", "tolerance_below"}) {
        double t = 0.0;  // moveit_msgs default
        if (auto value = constraint.Find(key)) {
          t = value->Number();
          if (t < 0.0) value->Fail("= " + FormatNumber(t) + " must be >= 0");
        }
        tolerance = std::min(tolerance, t);
      }
      if (robot_joints.count(name) == 0) continue;  // e.g. finger joints of a MoveIt model
      if (!targets.emplace(name, std::make_pair(position, tolerance)).second) {
        name_value.Fail("= '" + name + "' is constrained twice");
      }
    }
    if (targets.empty()) {
      ThrowInvalid(request_source + ": " + goal.path() + ".joint_constraints constrain none of the robot's joints (" +
                   JoinNames(robot.joint_names) + ")");
    }
    double tolerance = kMaxGoalTolerance;
    v1::JointGoal* joint_goal = request.mutable_goal();
    for (std::size_t i = 0; i < robot.joint_names.size(); ++i) {
      const auto it = targets.find(robot.joint_names[i]);
      if (it == targets.end()) {
        joint_goal->add_positions(request.start().positions(static_cast<int>(i)));  // as outside the planning group
      } else {
        joint_goal->add_positions(it->second.first);
        tolerance = std::min(tolerance, it->second.second);
      }
    }
    joint_goal->set_tolerance(tolerance);
    // A goal value outside a joint limit by no more than the goal's own tolerance (published
    // Fetch goals sit µrad beyond ±π) is clamped onto the limit by the server, which reports it:
    // bounds_tolerance (it covers the start too; capped at its 0.01 maximum).
    if (tolerance > 0.0) request.set_bounds_tolerance(std::min(tolerance, 0.01));
  }

  ReadPathConstraints(root, *scene.frames, robot, request.mutable_path_constraints());
  if (request.path_constraints().orientation_size() == 0 && request.path_constraints().position_size() == 0) {
    request.clear_path_constraints();
  }
  if (auto trajectory = root.Find("trajectory_constraints")) {
    RejectNonEmpty(*trajectory, "constraints", "trajectory constraints are not supported");
  }
  if (auto time = root.Find("allowed_planning_time")) {
    const double seconds = time->Number();
    if (seconds < 0.0 || seconds > kMaxTimeBudget) {
      time->Fail("= " + FormatNumber(seconds) + " must be within [0, 600] s (0 = Chasles' default budget)");
    }
    if (seconds > 0.0) request.set_time_budget(seconds);
  }
  *request.mutable_scene() = std::move(scene.scene);
  return request;
}

std::vector<MoveItProblem> ImportProblemDirectory(const std::string& directory, const RobotInfo& robot) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::is_directory(directory, error)) ThrowInvalid("'" + directory + "' is not a readable directory");
  // NNNN -> file names, from sceneNNNN.yaml and requestNNNN.yaml.
  std::map<std::string, std::string> scenes, requests;
  auto digits_of = [](const std::string& name, const std::string& prefix) -> std::optional<std::string> {
    const std::string suffix = ".yaml";
    if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
      return std::nullopt;
    }
    std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (!std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c); }))
      return std::nullopt;
    return digits;
  };
  fs::directory_iterator it(directory, error);
  if (error) ThrowInvalid("cannot list '" + directory + "': " + error.message());
  for (const fs::directory_entry& entry : it) {
    const std::string name = entry.path().filename().string();
    if (auto digits = digits_of(name, "scene")) scenes[*digits] = name;
    if (auto digits = digits_of(name, "request")) requests[*digits] = name;
  }
  for (const auto& [digits, name] : scenes) {
    if (requests.count(digits) == 0) {
      ThrowInvalid(directory + ": " + name + " has no request" + digits + ".yaml beside it");
    }
  }
  for (const auto& [digits, name] : requests) {
    if (scenes.count(digits) == 0) ThrowInvalid(directory + ": " + name + " has no scene" + digits + ".yaml beside it");
  }
  if (scenes.empty()) ThrowInvalid(directory + ": no sceneNNNN.yaml / requestNNNN.yaml pairs found");

  std::vector<std::string> order;
  for (const auto& [digits, name] : scenes) order.push_back(digits);
  // Numeric order (scene2 before scene10), then the text (scene01 before scene1).
  auto numeric = [](const std::string& digits) {
    const std::size_t first = digits.find_first_not_of('0');
    return first == std::string::npos ? std::string() : digits.substr(first);
  };
  std::sort(order.begin(), order.end(), [&numeric](const std::string& a, const std::string& b) {
    const std::string na = numeric(a), nb = numeric(b);
    if (na.size() != nb.size()) return na.size() < nb.size();
    if (na != nb) return na < nb;
    return a < b;
  });

  std::vector<MoveItProblem> problems;
  for (const std::string& digits : order) {
    const fs::path scene_path = fs::path(directory) / scenes[digits];
    const fs::path request_path = fs::path(directory) / requests[digits];
    MoveItProblem problem;
    problem.name = "scene" + digits;
    problem.request = ImportMotionPlanRequest(ReadFile(scene_path), ReadFile(request_path), robot, scene_path.string(),
                                              request_path.string());
    problems.push_back(std::move(problem));
  }
  return problems;
}

v1::JointTrajectory ImportJointTrajectory(const std::string& text, const std::string& source) {
  const YAML::Node root = ParseDocument(text, source, "trajectory_msgs/JointTrajectory or moveit_msgs/RobotTrajectory");
  Value top(root, "", &source);
  // A RobotTrajectory wraps it (its multi_dof part must be empty: Chasles has no such joints).
  if (std::optional<Value> wrapped = top.Find("joint_trajectory")) {
    if (std::optional<Value> multi = top.Find("multi_dof_joint_trajectory")) {
      if (std::optional<Value> points = multi->Find("points"); points && points->Count() > 0) {
        points->Fail("has " + std::to_string(points->Count()) + " points: multi-DOF joints are not supported");
      }
    }
    top = *wrapped;
  }
  v1::JointTrajectory out;
  for (const Value& name : top.Get("joint_names").Items()) out.add_joint_names(name.Text());
  const int n = out.joint_names_size();
  if (n == 0) top.Get("joint_names").Fail("is empty");
  for (const Value& point : top.Get("points").Items()) {
    v1::TrajectoryPoint* p = out.add_points();
    const auto fill = [&](const char* key, google::protobuf::RepeatedField<double>* values, bool required) {
      const std::optional<Value> list = point.Find(key);
      if (!list || list->Count() == 0) {
        if (required) point.Get(key).Fail("is empty");
        return;
      }
      if (static_cast<int>(list->Count()) != n) {
        list->Fail("has " + std::to_string(list->Count()) + " values for " + std::to_string(n) + " joint_names");
      }
      for (const Value& v : list->Items()) values->Add(v.Number());
    };
    fill("positions", p->mutable_positions(), true);
    fill("velocities", p->mutable_velocities(), false);
    fill("accelerations", p->mutable_accelerations(), false);
    // time_from_start: {sec, nanosec} (ROS 2), {secs, nsecs} (ROS 1) or seconds.
    const Value time = point.Get("time_from_start");
    double seconds = 0.0;
    if (time.node().IsScalar()) {
      seconds = time.Number();
    } else {
      const std::optional<Value> sec = time.Find("sec") ? time.Find("sec") : time.Find("secs");
      const std::optional<Value> nsec = time.Find("nanosec") ? time.Find("nanosec") : time.Find("nsecs");
      if (!sec && !nsec) time.Fail("must be seconds or {sec, nanosec}");
      seconds = (sec ? sec->Number() : 0.0) + 1e-9 * (nsec ? nsec->Number() : 0.0);
    }
    p->set_time_from_start(seconds);
  }
  if (out.points_size() == 0) top.Get("points").Fail("is empty");
  return out;
}

}  // namespace chasles::moveit
