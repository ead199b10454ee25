#include "chasles/collision/robot_spheres.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <string>
#include <system_error>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "chasles/collision/shape_spheres.h"
#include "chasles/robot/error.h"

namespace chasles {
namespace {

/// One shape to fit: link `link`'s collision[shape] with its share of the link's budget.
struct Job {
  int link = 0;
  int shape = 0;
  SphereFitOptions fit;
  int same_as = -1;  // an earlier job with the very same shape and budget: its spheres are these
  FittedSpheres spheres;
  std::exception_ptr error;
};

/// True when `a` and `b` are the same shape to fit (poses aside) with the same options: a
/// primitive of equal type and dimensions, or the same mesh object.
bool SameFit(const Shape& a, const Shape& b, const SphereFitOptions& fa, const SphereFitOptions& fb) {
  if (a.type != b.type || fa.max_spheres != fb.max_spheres) return false;
  if (a.type == ShapeType::kMesh) return a.mesh == b.mesh;
  return std::tie(a.radius, a.length) == std::tie(b.radius, b.length) && a.size == b.size;
}

/// A rough measure of a fit's work, to start the longest first: a voxel fit (box, mesh) grows
/// with its extent; a cylinder's or capsule's cover is cheap.
double Work(const Shape& shape) {
  switch (shape.type) {
    case ShapeType::kBox:
      return 1.0 + shape.size.maxCoeff();
    case ShapeType::kMesh: {
      if (shape.mesh == nullptr || shape.mesh->vertices.empty()) return 1.0;
      Eigen::Vector3d lo = shape.mesh->vertices[0], hi = lo;
      for (const Eigen::Vector3d& v : shape.mesh->vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
      return 1.0 + (hi - lo).maxCoeff();
    }
    default:
      return 0.0;
  }
}

/// Runs every job that is not a copy on up to `threads` threads, the most work first (each
/// thread takes the next job left). Which thread fits a shape does not change its spheres.
void RunJobs(const std::vector<Link>& links, std::vector<Job>* jobs, int threads) {
  std::vector<std::pair<double, std::size_t>> order;
  for (std::size_t j = 0; j < jobs->size(); ++j) {
    const Job& job = (*jobs)[j];
    if (job.same_as < 0) order.emplace_back(-Work(links[job.link].collision[job.shape]), j);
  }
  std::stable_sort(order.begin(), order.end());
  std::vector<std::size_t> work;
  for (const auto& [cost, j] : order) work.push_back(j);
  std::atomic<std::size_t> next{0};
  const auto run = [&] {
    for (std::size_t k = next++; k < work.size(); k = next++) {
      Job& job = (*jobs)[work[k]];
      try {
        job.spheres = FitShapeSpheres(links[job.link].collision[job.shape], job.fit);
      } catch (...) {
        job.error = std::current_exception();
      }
    }
  };
  const int extra = std::min(threads, static_cast<int>(work.size())) - 1;
  std::vector<std::thread> pool;
  for (int t = 0; t < extra; ++t) {
    try {
      pool.emplace_back(run);
    } catch (const std::system_error&) {
      break;  // no thread to be had: fewer do the same work
    }
  }
  run();
  for (std::thread& t : pool) t.join();
}

}  // namespace

void RobotSphereOptions::Validate() const {
  fit.Validate();
  if (max_spheres_per_link < 1) {
    ThrowInvalid("sphere_fit.max_spheres_per_link = " + std::to_string(max_spheres_per_link) + " must be >= 1");
  }
  if (threads < 0) ThrowInvalid("sphere_fit.threads = " + std::to_string(threads) + " must be >= 0");
}

RobotSphereFit FitRobotSpheres(const RobotModel& robot, const RobotSphereOptions& options) {
  options.Validate();
  RobotSphereFit out;
  bool has_mesh = false;
  for (const Link& link : robot.links()) {
    for (const Shape& shape : link.collision) has_mesh = has_mesh || shape.type == ShapeType::kMesh;
  }
  if (!has_mesh) return out;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Link> links = robot.links();

  // The shapes to fit, each link's budget shared among its shapes that are fitted.
  std::vector<Job> jobs;
  for (std::size_t l = 0; l < links.size(); ++l) {
    const std::vector<Shape>& shapes = links[l].collision;
    const int to_fit = static_cast<int>(std::count_if(
        shapes.begin(), shapes.end(), [](const Shape& s) { return s.type != ShapeType::kSphere; }));
    for (std::size_t s = 0; s < shapes.size(); ++s) {
      if (shapes[s].type == ShapeType::kSphere) continue;
      Job job;
      job.link = static_cast<int>(l);
      job.shape = static_cast<int>(s);
      job.fit = options.fit;
      job.fit.max_spheres = std::max(1, options.max_spheres_per_link / to_fit);
      for (std::size_t k = 0; k < jobs.size() && job.same_as < 0; ++k) {
        const Shape& other = links[jobs[k].link].collision[jobs[k].shape];
        if (jobs[k].same_as < 0 && SameFit(shapes[s], other, job.fit, jobs[k].fit)) job.same_as = static_cast<int>(k);
      }
      jobs.push_back(std::move(job));
    }
  }
  const int threads = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  RunJobs(links, &jobs, std::max(1, threads));

  for (Job& job : jobs) {
    const Job& done = job.same_as < 0 ? job : jobs[job.same_as];
    if (done.error) {
      const std::string where = "link '" + links[job.link].name + "' collision[" + std::to_string(job.shape) + "]: ";
      try {
        std::rethrow_exception(done.error);
      } catch (const Error& e) {
        throw Error(e.code(), where + e.what());
      }
    }
    if (job.same_as >= 0) job.spheres = done.spheres;
    ++out.shapes_fitted;
    if (job.spheres.reach > out.reach) {
      out.reach = job.spheres.reach;
      out.reach_link = links[job.link].name;
    }
  }
  // Each link's collision, shape by shape: a sphere as it was, a fitted shape as its spheres
  // (placed in the link's frame). Jobs are in link and shape order.
  std::size_t next_job = 0;
  for (std::size_t l = 0; l < links.size(); ++l) {
    std::vector<Shape> spheres;
    for (const Shape& shape : links[l].collision) {
      if (shape.type == ShapeType::kSphere) {
        spheres.push_back(shape);
        continue;
      }
      const FittedSpheres& fitted = jobs[next_job++].spheres;
      for (std::size_t i = 0; i < fitted.centres.size(); ++i) {
        spheres.push_back(Shape::Sphere(fitted.radii[i], shape.pose * Eigen::Translation3d(fitted.centres[i])));
      }
    }
    links[l].collision = std::move(spheres);
  }
  for (const Link& link : links) out.spheres += static_cast<int>(link.collision.size());
  // The allowed pairs as the robot has them (FromTree adds parent/child pairs again).
  std::vector<std::pair<std::string, std::string>> allowed;
  const int n = robot.num_links();
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      if (robot.allowed_collisions().IsAllowed(a, b)) allowed.emplace_back(links[a].name, links[b].name);
    }
  }
  out.model = RobotModel::FromTree(robot.name(), std::move(links), robot.joints(), allowed, robot.motion(),
                                   robot.load_warnings());
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace chasles
