// The per-frame files of a results folder (layout in docs/formats.md, "Results layout"):
// 8-bit colour PNGs, 16-bit depth PNGs, float32 depth .npy, coloured PLY point clouds and
// heat-map PNGs. Images are row-major, top row first. Every writer throws Error(kUnavailable)
// naming the path when the file cannot be written, and InvalidArgument on a size that disagrees
// with width x height.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "worker/engine/eval/point_cloud.h"

namespace endorecon::eval {

// The name of frame `index` inside a results subfolder: six zero-padded digits, then
// `extension` ("000012.png" for 12, ".png"). Throws InvalidArgument for a negative index.
std::string FrameFileName(int index, std::string_view extension);

// Float RGB (width*height*3, [0, 1]) as an 8-bit RGB PNG: clamped, rounded, NaN as 0.
void WritePng8(const std::filesystem::path& path, std::span<const float> rgb, int width, int height);

// The depth PNG scale that fits [0, far] into 16 bits: 65535 / far. Throws InvalidArgument
// unless far is finite and > 0.
double DepthPngScale(double far);

// A ray whose opacity stays under this met no surface: the render composites the far plane into its
// depth (render/frame_renderer.h), which the results files would show as a wall at far.
inline constexpr float kSurfaceOpacity = 0.5f;

// The depth the results files hold: 0 ("no depth") where the ray met no surface (its opacity under
// kSurfaceOpacity: a view past the scene, an object capture's background), the rendered depth elsewhere.
void ClearDepthWithoutSurface(std::span<float> depth, std::span<const float> opacity);

// Depth (width*height, clip units) as a 16-bit grey PNG: value = round(depth * scale), clamped to
// [0, 65535]; non-finite or negative depth is 0 (0 means "no depth", as in the clip layouts).
// A reader recovers depth = value / scale; the caller records `scale` in metrics.json.
void WriteDepthPng16(const std::filesystem::path& path, std::span<const float> depth, int width, int height,
                     double scale);

// Depth (width*height) as a float32 .npy of shape (height, width), values as given.
void WriteDepthNpy(const std::filesystem::path& path, std::span<const float> depth, int width, int height);

// A binary little-endian PLY: element vertex with float x, y, z and uchar red, green, blue.
void WritePly(const std::filesystem::path& path, const PointCloud& cloud);

// Values (width*height) as a colour PNG through the perceptual "inferno" colour map: vmin is black,
// vmax pale yellow, values outside clamped; non-finite values are mid-grey. Use one (vmin, vmax)
// for every frame of a clip so colours compare across frames. Throws InvalidArgument unless
// vmax > vmin.
void WriteHeatmapPng(const std::filesystem::path& path, std::span<const float> values, int width, int height,
                     double vmin, double vmax);

// A heat-map upper bound for a whole clip: the `quantile` (in (0, 1]) of the finite values of
// every frame together, so a few outliers do not wash out the rest. Returns 1 when there is no
// finite value or that quantile is not positive (an all-zero error map), so [0, bound] is never empty.
double HeatmapUpperBound(std::span<const std::vector<float>> frames, double quantile = 0.99);

// The same bound gathered frame by frame, so a clip's maps need not stay in memory until the last
// frame: of `values_in_all` values (the clip's frames times their pixels) every k-th is kept, k the
// least that keeps at most `most_kept` (every value, and the same bound as HeatmapUpperBound, up to
// that; 4 M values, 16 MB, by default: a clip of 48 frames of 640 x 512 still keeps every value).
class HeatmapScale {
 public:
  explicit HeatmapScale(std::size_t values_in_all, std::size_t most_kept = std::size_t{1} << 22);
  // `left_out` (a tool mask, nonzero where left out; empty: none) keeps its pixels out of the scale:
  // a tool's error, 5% of a frame, set the error maps' bound and left the tissue near black.
  void Add(std::span<const float> frame, std::span<const std::uint8_t> left_out = {});
  double UpperBound(double quantile = 0.99) const;
  std::size_t stride() const { return stride_; }

 private:
  std::size_t stride_;
  std::size_t next_ = 0;  // the index in the next frame of the next value kept
  std::vector<float> kept_;
};

}  // namespace endorecon::eval
