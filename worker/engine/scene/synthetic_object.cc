#include "worker/engine/scene/synthetic_object.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "worker/engine/scene/alpha_composite.h"
#include "worker/engine/scene/portable_random.h"
#include "worker/engine/scene/synthetic_files.h"
#include "worker/engine/scene/transforms_clip.h"

namespace endorecon::scene {
namespace {

using Eigen::Vector3d;
using Rgb = std::array<float, 3>;

constexpr double kCameraDistance = 4.0;
constexpr double kCameraAngleX = 0.6911112070083618;  // NeRF's lego
constexpr double kMinElevationDeg = 5, kMaxElevationDeg = 75;
constexpr int kSubsamples = 3;  // per pixel and axis

// The object's parts (world units, z up).
const Vector3d kBallCentre(0, 0, 0.15);
constexpr double kBallRadius = 0.85;
const Vector3d kPedestalMin(-1.1, -1.1, -1.0), kPedestalMax(1.1, 1.1, -0.7);
const Vector3d kMarbleCentre(0.75, -0.75, -0.5);
constexpr double kMarbleRadius = 0.2;

struct Hit {
  double t = INFINITY;
  Vector3d normal;
  Rgb albedo{};
};

std::optional<double> SphereHit(const Vector3d& o, const Vector3d& d, const Vector3d& centre, double radius) {
  const Vector3d oc = o - centre;
  const double b = oc.dot(d), c = oc.squaredNorm() - radius * radius;
  const double disc = b * b - c;
  if (disc < 0) return std::nullopt;
  const double t = -b - std::sqrt(disc);
  return t > 0 ? std::optional<double>(t) : std::nullopt;
}

// Longitude segments in two colours, darker latitude bands and a fine dot pattern: texture at
// several scales for the hash grid to fit.
Rgb BallAlbedo(const Vector3d& n) {
  const double azimuth = std::atan2(n.y(), n.x()), polar = std::acos(std::clamp(n.z(), -1.0, 1.0));
  const int segment = int(std::floor((azimuth + std::numbers::pi) / (std::numbers::pi / 4)));
  Rgb c = segment % 2 == 0 ? Rgb{0.10f, 0.60f, 0.62f} : Rgb{0.92f, 0.52f, 0.12f};
  if (int(std::floor(polar / 0.3)) % 2 == 1) {
    for (float& v : c) v *= 0.7f;
  }
  if (std::sin(24 * azimuth) * std::sin(24 * polar) > 0.85) c = {0.95f, 0.95f, 0.9f};
  return c;
}

Rgb PedestalAlbedo(const Vector3d& p, const Vector3d& normal) {
  if (normal.z() < 0.5) return {0.15f, 0.2f, 0.45f};
  const int checker = int(std::floor(p.x() / 0.22)) + int(std::floor(p.y() / 0.22));
  return (checker & 1) ? Rgb{0.82f, 0.8f, 0.75f} : Rgb{0.3f, 0.3f, 0.32f};
}

// Slab test against the pedestal; the face normal of the entry.
void PedestalHit(const Vector3d& o, const Vector3d& d, Hit& best) {
  double enter = 0, leave = INFINITY;
  int axis = -1;
  double sign = 0;
  for (int c = 0; c < 3; ++c) {
    if (d[c] == 0) {
      if (o[c] < kPedestalMin[c] || o[c] > kPedestalMax[c]) return;
      continue;
    }
    double t0 = (kPedestalMin[c] - o[c]) / d[c], t1 = (kPedestalMax[c] - o[c]) / d[c];
    const double entry_sign = t0 < t1 ? -1 : 1;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > enter) {
      enter = t0;
      axis = c;
      sign = entry_sign;
    }
    leave = std::min(leave, t1);
  }
  if (axis < 0 || !(enter < leave) || enter >= best.t) return;
  best.t = enter;
  best.normal = Vector3d::Zero();
  best.normal[axis] = sign;
  best.albedo = PedestalAlbedo(o + enter * d, best.normal);
}

// The colour of one ray (d unit), or nothing when it misses the object.
std::optional<Rgb> Trace(const Vector3d& o, const Vector3d& d) {
  Hit hit;
  if (const auto t = SphereHit(o, d, kBallCentre, kBallRadius)) {
    hit.t = *t;
    hit.normal = (o + *t * d - kBallCentre).normalized();
    hit.albedo = BallAlbedo(hit.normal);
  }
  if (const auto t = SphereHit(o, d, kMarbleCentre, kMarbleRadius); t && *t < hit.t) {
    hit.t = *t;
    hit.normal = (o + *t * d - kMarbleCentre).normalized();
    hit.albedo = {0.85f, 0.1f, 0.1f};
  }
  PedestalHit(o, d, hit);
  if (!std::isfinite(hit.t)) return std::nullopt;
  const Vector3d light = Vector3d(0.3, 0.5, 1.0).normalized();
  const float shade = float(0.3 + 0.7 * std::max(0.0, hit.normal.dot(light)));
  return Rgb{hit.albedo[0] * shade, hit.albedo[1] * shade, hit.albedo[2] * shade};
}

// Camera-to-world (OpenGL axes: x right, y up, looking down -z) of a camera at `position` looking at
// the origin with the world's z up.
Eigen::Matrix4d LookAtOrigin(const Vector3d& position) {
  const Vector3d back = position.normalized();
  const Vector3d right = Vector3d::UnitZ().cross(back).normalized();
  const Vector3d up = back.cross(right);
  Eigen::Matrix4d c2w = Eigen::Matrix4d::Identity();
  c2w.block<3, 1>(0, 0) = right;
  c2w.block<3, 1>(0, 1) = up;
  c2w.block<3, 1>(0, 2) = back;
  c2w.block<3, 1>(0, 3) = position;
  return c2w;
}

}  // namespace

// Smooth, as light from far away is, with a soft lobe toward a window (a kink where the lobe ends,
// so a band-limited background fits it closely but not exactly).
void BackdropColor(const double* d, float* rgb) {
  const double window = std::max(0.0, 0.6 * d[0] + 0.48 * d[1] + 0.64 * d[2]);
  const double lobe = 0.35 * window * window;
  rgb[0] = float(std::clamp(0.45 + 0.25 * d[2] + 0.1 * d[0] + lobe, 0.0, 1.0));
  rgb[1] = float(std::clamp(0.40 + 0.2 * d[2] - 0.1 * d[1] + lobe, 0.0, 1.0));
  rgb[2] = float(std::clamp(0.35 + 0.3 * d[2] + 0.15 * d[0] * d[1] + 0.8 * lobe, 0.0, 1.0));
}

SyntheticObjectViews RenderSyntheticObject(const ObjectSynthOptions& options) {
  if (options.views < 1 || options.width < 1 || options.height < 1) {
    FailInvalid("synthetic object: need at least one view of at least 1 x 1 pixels, got " +
                std::to_string(options.views) + " views of " + std::to_string(options.width) + " x " +
                std::to_string(options.height));
  }
  SyntheticObjectViews views;
  views.width = options.width;
  views.height = options.height;
  views.channels = options.backdrop ? 3 : 4;
  PortableRandom random(options.seed);
  const double focal = 0.5 * options.width / std::tan(0.5 * kCameraAngleX);
  const double cx = 0.5 * options.width, cy = 0.5 * options.height;
  for (int view = 0; view < options.views; ++view) {
    const double azimuth = random.Uniform(0, 2 * std::numbers::pi);
    // Uniform over the band of the sphere between the two elevations.
    const double lo = std::sin(kMinElevationDeg * std::numbers::pi / 180);
    const double hi = std::sin(kMaxElevationDeg * std::numbers::pi / 180);
    const double elevation = std::asin(random.Uniform(lo, hi));
    const Vector3d position =
        kCameraDistance * Vector3d(std::cos(elevation) * std::cos(azimuth),
                                   std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    const Eigen::Matrix4d c2w = LookAtOrigin(position);
    const Eigen::Matrix3d rotation = c2w.block<3, 3>(0, 0);
    std::array<double, 16> matrix;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) matrix[4 * r + c] = c2w(r, c);
    }
    views.c2w.push_back(matrix);
    const int channels = views.channels;
    std::vector<std::uint8_t> image(std::size_t(options.width) * options.height * channels);
    tbb::parallel_for(0, options.height, [&](int v) {
      for (int u = 0; u < options.width; ++u) {
        Rgb sum{};
        int hits = 0;
        for (int i = 0; i < kSubsamples * kSubsamples; ++i) {
          // Pixel (u, v) spans [u, u + 1) x [v, v + 1): its centre is where the loader's ray goes
          // (scene/view_geometry.h PixelRay).
          const double su = u + (i % kSubsamples + 0.5) / kSubsamples;
          const double sv = v + (i / kSubsamples + 0.5) / kSubsamples;
          const Vector3d direction =
              (rotation * Vector3d((su - cx) / focal, -(sv - cy) / focal, -1)).normalized();
          if (const auto rgb = Trace(position, direction)) {
            for (int c = 0; c < 3; ++c) sum[c] += (*rgb)[c];
            ++hits;
          } else if (options.backdrop) {
            float rgb[3];
            BackdropColor(direction.data(), rgb);
            for (int c = 0; c < 3; ++c) sum[c] += rgb[c];
          }
        }
        std::uint8_t* pixel = &image[(std::size_t(v) * options.width + u) * channels];
        if (options.backdrop) {
          constexpr float k = 1.0f / (kSubsamples * kSubsamples);
          for (int c = 0; c < 3; ++c) pixel[c] = ToByte(sum[c] * k);
          continue;
        }
        const float k = hits > 0 ? 1.0f / float(hits) : 0.0f;  // straight alpha: the hits' mean colour
        for (int c = 0; c < 3; ++c) pixel[c] = ToByte(sum[c] * k);
        pixel[3] = ToByte(float(hits) / (kSubsamples * kSubsamples));
      }
    });
    views.images.push_back(std::move(image));
  }
  return views;
}

nlohmann::json SyntheticObjectTransforms(const SyntheticObjectViews& views) {
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& c2w : views.c2w) {
    nlohmann::json matrix = nlohmann::json::array();
    for (int r = 0; r < 4; ++r)
      matrix.push_back({c2w[4 * r], c2w[4 * r + 1], c2w[4 * r + 2], c2w[4 * r + 3]});
    frames.push_back({{"transform_matrix", matrix}});
  }
  return {{"camera_angle_x", kCameraAngleX}, {"frames", frames}};
}

Clip MakeSyntheticObject(const ObjectSynthOptions& options,
                         const std::array<std::uint8_t, 3>& alpha_background) {
  const SyntheticObjectViews views = RenderSyntheticObject(options);
  Clip clip;
  clip.source = "synthetic object (in memory)";
  clip.width = views.width;
  clip.height = views.height;
  const std::size_t pixels = std::size_t(views.width) * views.height;
  for (const auto& image : views.images) {
    if (views.channels == 3) {
      clip.rgb.push_back(image);
      continue;
    }
    std::vector<std::uint8_t> rgb(3 * pixels);
    clip.transparent =
        CompositeRgbaOnto(image.data(), pixels, alpha_background, rgb.data()) || clip.transparent;
    clip.rgb.push_back(std::move(rgb));
  }
  FinishTransformsClip(SyntheticObjectTransforms(views), clip.source, clip);
  return clip;
}

}  // namespace endorecon::scene
