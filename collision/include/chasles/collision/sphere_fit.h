#pragma once
/// \file
/// A conservative sphere decomposition of a triangle mesh, so a link given as a mesh can be
/// checked on the sphere path: the spheres cover the mesh's solid — proven, not sampled — and
/// reach at most a reported, proven distance outside it.

#include <vector>

#include <Eigen/Core>

#include "chasles/robot/geometry.h"

namespace chasles {

/// How finely FitSpheres may approximate a mesh.
struct SphereFitOptions {
  /// [m] target bound on how far the spheres may reach outside the shape, finite and > 0. When
  /// max_spheres cannot meet it (or the grid is too coarse for it), the bound is relaxed step by
  /// step; FittedSpheres::reach says what was achieved.
  double max_reach = 0.01;
  /// Spheres per shape, >= 1.
  int max_spheres = 32;
  /// Grid resolution cap, within [4, 256]: the voxel edge is at least the mesh's largest extent
  /// divided by this (bounds time and memory: about 60 bytes per voxel, a little over cap³ voxels
  /// at most), and at least max_reach / 6.
  int max_voxels_per_axis = 96;

  /// \throws Error(kInvalidArgument) naming the field, its value and the rule, e.g.
  ///         `sphere_fit.max_spheres = 0 must be >= 1`.
  void Validate() const;
};

/// Spheres in the mesh's frame, `centres[i]` with `radii[i]`.
struct FittedSpheres {
  std::vector<Eigen::Vector3d> centres;  ///< in the mesh's frame [m]
  std::vector<double> radii;             ///< [m], > 0
  /// [m] a proven upper bound on the distance from any point of any sphere to the mesh's solid
  /// (its triangles, plus the volume they enclose when the mesh is closed).
  double reach = 0.0;
};

/// Covers `mesh` with at most `options.max_spheres` spheres.
///
/// Guarantee: every point of every triangle lies inside (or on) at least one sphere, and so does
/// every point the mesh encloses when it is closed — by construction, not by sampling. A mesh is
/// closed when every edge (between vertices welded when within 1e-12 of the mesh's extent of each
/// other, so that a single-precision export's seam still closes) is shared by an even number of
/// triangles (two, for a manifold); its enclosed volume is the set of points an odd number of its
/// (welded) triangles separate from infinity (ray parity). An open mesh is its triangles only.
/// Degenerate meshes (a single triangle, coplanar or collinear points, one point) are fine.
///
/// The reach is measured on the spheres found, against the mesh itself (not only on the grid), so
/// it is close to the true largest distance: e.g. 0.9–1.7 cm for the UR5's 96-sided cylinders,
/// 0.08–0.15 m across, with a budget of 40 spheres each, of which 26–32 are kept
/// (examples/robots/ur5_meshes).
///
/// Time and memory grow with the grid (options.max_voxels_per_axis cubed, or max_reach / 6 per
/// voxel when that is coarser) and the triangle count: about 0.2–1.5 s for a 960-triangle
/// cylinder at the defaults with 40 spheres on one core, more when a tight budget forces the reach
/// to relax over several grids. Thread-safe (no state).
/// \throws Error(kInvalidArgument) when options are invalid (SphereFitOptions::Validate), the mesh
///         has no triangles, a triangle refers to a vertex out of range
///         (`mesh.triangles[4][2] = 9 is out of range [0, 8)`), or a vertex is not finite
///         (`mesh.vertices[3] = (nan, 0, 1) must be finite`).
FittedSpheres FitSpheres(const TriangleMesh& mesh, const SphereFitOptions& options = {});

}  // namespace chasles
