// The tissue surface of one rendered frame as a triangle mesh: the frame's depth triangulated on
// the pixel grid (the canonical frame's, t = 0, in the results), written as PLY, OBJ and STL.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "worker/engine/scene/camera.h"

namespace endorecon::eval {

struct SurfaceMesh {
  std::vector<float> xyz;         // 3 per vertex, world coordinates, clip units
  std::vector<std::uint8_t> rgb;  // 3 per vertex
  std::vector<std::uint32_t>
      triangles;  // 3 vertex indices per triangle, counter-clockwise seen from the camera
  std::size_t vertex_count() const { return xyz.size() / 3; }
  std::size_t triangle_count() const { return triangles.size() / 3; }
};

// Each pixel with a known surface (not a tool pixel, depth finite, > 0 and below `far`, where the
// renderer puts rays that hit nothing) is a vertex, back-projected as eval::BackProject does. Each
// 2x2 block of pixels gives the triangles whose three corners are vertices, except across a depth
// edge (a triangle whose largest depth exceeds its smallest by more than `max_depth_jump`, a
// fraction), so the tissue is not bridged to what lies behind a fold. Throws InvalidArgument when a
// size disagrees with the camera's.
SurfaceMesh TriangulateDepth(const scene::Camera& camera, std::span<const float> depth,
                             std::span<const float> rgb, std::span<const std::uint8_t> tool_mask, double far,
                             double max_depth_jump = 0.1);

// Binary little-endian PLY: vertices (float x, y, z, uchar red, green, blue), faces (uchar count,
// int indices). Throws Error(kUnavailable) naming the file when it cannot be written.
void WriteMeshPly(const std::filesystem::path& path, const SurfaceMesh& mesh);
// Wavefront OBJ with per-vertex colours ("v x y z r g b", colours in [0, 1]) and 1-based faces.
void WriteMeshObj(const std::filesystem::path& path, const SurfaceMesh& mesh);
// Binary STL (facet normals from the vertex order, no colour).
void WriteMeshStl(const std::filesystem::path& path, const SurfaceMesh& mesh);
// mesh.ply, mesh.obj and mesh.stl in `folder`.
void WriteSurfaceMesh(const std::filesystem::path& folder, const SurfaceMesh& mesh);

}  // namespace endorecon::eval
