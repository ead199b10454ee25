#pragma once
/// \file
/// Mesh input (STL, OBJ, COLLADA) through assimp.

#include <memory>
#include <string>

#include <Eigen/Core>

#include "chasles/robot/geometry.h"
#include "chasles/robot/input_limits.h"

namespace chasles {

/// Parses STL (ASCII or binary), OBJ or COLLADA (.dae: XML with a <COLLADA> root) bytes with
/// assimp (aiProcess_Triangulate | aiProcess_JoinIdenticalVertices), applying `scale` per axis.
/// COLLADA: every node's transform and the document's <unit meter=…> are applied; <up_axis> is
/// not (the axes stay as written, Z up as in robot description files — what RViz and MoveIt do).
/// `field` names the input in error messages, e.g. `scene.meshes[1].data`.
/// \throws Error(kInvalidArgument) when assimp cannot read the bytes, the mesh holds no
///         triangles, or a scale component is not finite and > 0.
/// \throws Error(kResourceExhausted) when the bytes are more than `limits.max_document_bytes`,
///         or the mesh holds more than `limits.max_mesh_triangles` triangles or
///         `limits.max_mesh_vertices` vertices (checked from a binary STL's header before
///         assimp reads it, and from assimp's counts before anything is copied).
std::shared_ptr<const TriangleMesh> ParseMesh(const std::string& bytes, const Eigen::Vector3d& scale,
                                              const std::string& field, const InputLimits& limits = {});

}  // namespace chasles
