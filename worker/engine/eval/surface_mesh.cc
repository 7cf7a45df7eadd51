#include "worker/engine/eval/surface_mesh.h"

#include <Eigen/Geometry>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "common/error.h"
#include "worker/engine/eval/image_size.h"
#include "worker/engine/eval/quantize.h"

namespace endorecon::eval {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

void Finish(std::ofstream& out, const std::filesystem::path& path) {
  out.close();
  if (!out) Fail(ErrorCode::kUnavailable, "cannot write mesh " + path.string());
}

Eigen::Vector3f Vertex(const SurfaceMesh& mesh, std::uint32_t index) {
  return {mesh.xyz[3 * index], mesh.xyz[3 * index + 1], mesh.xyz[3 * index + 2]};
}

}  // namespace

SurfaceMesh TriangulateDepth(const scene::Camera& camera, std::span<const float> depth,
                             std::span<const float> rgb, std::span<const std::uint8_t> tool_mask, double far,
                             double max_depth_jump) {
  const int w = camera.width, h = camera.height;
  CheckImageSize(depth.size(), w, h, 1, "mesh: depth");
  CheckImageSize(rgb.size(), w, h, 3, "mesh: colour");
  CheckMaskSize(tool_mask.size(), w, h, "mesh: tool mask");
  SurfaceMesh mesh;
  std::vector<std::uint32_t> index(depth.size(), kNone);
  Eigen::Vector3d origin, direction;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t p = static_cast<std::size_t>(v) * w + u;
      const float z = depth[p];
      if ((!tool_mask.empty() && tool_mask[p] != 0) || !std::isfinite(z) || z <= 0 || z >= far) continue;
      camera.Ray(u, v, origin, direction);
      const Eigen::Vector3d point = origin + static_cast<double>(z) * direction;
      index[p] = static_cast<std::uint32_t>(mesh.vertex_count());
      for (int c = 0; c < 3; ++c) {
        mesh.xyz.push_back(static_cast<float>(point[c]));
        mesh.rgb.push_back(ToByte(rgb[3 * p + c]));
      }
    }
  }
  const auto add = [&](std::size_t a, std::size_t b, std::size_t c) {
    if (index[a] == kNone || index[b] == kNone || index[c] == kNone) return;
    const float lo = std::min({depth[a], depth[b], depth[c]}), hi = std::max({depth[a], depth[b], depth[c]});
    if (hi > lo * (1 + max_depth_jump)) return;
    mesh.triangles.insert(mesh.triangles.end(), {index[a], index[b], index[c]});
  };
  for (int v = 0; v + 1 < h; ++v) {
    for (int u = 0; u + 1 < w; ++u) {
      const std::size_t p00 = static_cast<std::size_t>(v) * w + u, p01 = p00 + 1, p10 = p00 + w,
                        p11 = p10 + 1;
      // Image rows run down while camera y runs up, so (p00, p10, p01) is counter-clockwise seen
      // from the camera.
      add(p00, p10, p01);
      add(p01, p10, p11);
    }
  }
  return mesh;
}

void WriteMeshPly(const std::filesystem::path& path, const SurfaceMesh& mesh) {
  static_assert(std::endian::native == std::endian::little, "PLY values are written as stored in memory");
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << "ply\nformat binary_little_endian 1.0\ncomment endorecon tissue surface mesh, clip units\n"
      << "element vertex " << mesh.vertex_count() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      << "element face " << mesh.triangle_count() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    out.write(reinterpret_cast<const char*>(&mesh.xyz[3 * i]), 3 * sizeof(float));
    out.write(reinterpret_cast<const char*>(&mesh.rgb[3 * i]), 3);
  }
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint8_t three = 3;
    out.write(reinterpret_cast<const char*>(&three), 1);
    for (int k = 0; k < 3; ++k) {
      const auto vertex = static_cast<std::int32_t>(mesh.triangles[3 * t + k]);
      out.write(reinterpret_cast<const char*>(&vertex), sizeof(vertex));
    }
  }
  Finish(out, path);
}

void WriteMeshObj(const std::filesystem::path& path, const SurfaceMesh& mesh) {
  std::ofstream out(path, std::ios::trunc);
  out << "# endorecon tissue surface mesh, clip units; vertex colours in [0, 1]\n";
  char line[160];
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    std::snprintf(line, sizeof(line), "v %.6g %.6g %.6g %.4f %.4f %.4f\n", mesh.xyz[3 * i],
                  mesh.xyz[3 * i + 1], mesh.xyz[3 * i + 2], mesh.rgb[3 * i] / 255.0,
                  mesh.rgb[3 * i + 1] / 255.0, mesh.rgb[3 * i + 2] / 255.0);
    out << line;
  }
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    out << "f " << mesh.triangles[3 * t] + 1 << ' ' << mesh.triangles[3 * t + 1] + 1 << ' '
        << mesh.triangles[3 * t + 2] + 1 << '\n';
  }
  Finish(out, path);
}

void WriteMeshStl(const std::filesystem::path& path, const SurfaceMesh& mesh) {
  static_assert(std::endian::native == std::endian::little, "STL values are written as stored in memory");
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  char header[80] = {};
  std::strncpy(header, "endorecon tissue surface mesh, clip units", sizeof(header) - 1);
  out.write(header, sizeof(header));
  const auto count = static_cast<std::uint32_t>(mesh.triangle_count());
  out.write(reinterpret_cast<const char*>(&count), sizeof(count));
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Eigen::Vector3f a = Vertex(mesh, mesh.triangles[3 * t]),
                          b = Vertex(mesh, mesh.triangles[3 * t + 1]),
                          c = Vertex(mesh, mesh.triangles[3 * t + 2]);
    const Eigen::Vector3f normal = (b - a).cross(c - a).normalized();
    float facet[12];
    for (int k = 0; k < 3; ++k) {
      facet[k] = normal[k];
      facet[3 + k] = a[k];
      facet[6 + k] = b[k];
      facet[9 + k] = c[k];
    }
    out.write(reinterpret_cast<const char*>(facet), sizeof(facet));
    const std::uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), sizeof(attributes));
  }
  Finish(out, path);
}

void WriteSurfaceMesh(const std::filesystem::path& folder, const SurfaceMesh& mesh) {
  WriteMeshPly(folder / "mesh.ply", mesh);
  WriteMeshObj(folder / "mesh.obj", mesh);
  WriteMeshStl(folder / "mesh.stl", mesh);
}

}  // namespace endorecon::eval
