#include "worker/engine/scene/synthetic_object.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/core.hpp>
#include <optional>

#include "worker/engine/scene/portable_random.h"
#include "worker/engine/scene/synthetic_files.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;
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

void WriteSyntheticObject(const ObjectSynthOptions& options, const fs::path& dir) {
  ClearSyntheticFolder(dir);
  fs::create_directories(dir / "images");
  PortableRandom random(options.seed);
  const double focal = 0.5 * options.width / std::tan(0.5 * kCameraAngleX);
  const double cx = 0.5 * options.width, cy = 0.5 * options.height;
  nlohmann::json frames = nlohmann::json::array();
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
    cv::Mat image(options.height, options.width, options.backdrop ? CV_8UC3 : CV_8UC4);
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
        if (options.backdrop) {
          constexpr float k = 1.0f / (kSubsamples * kSubsamples);
          image.at<cv::Vec3b>(v, u) = {ToByte(sum[2] * k), ToByte(sum[1] * k), ToByte(sum[0] * k)};
          continue;
        }
        const float k = hits > 0 ? 1.0f / float(hits) : 0.0f;  // straight alpha: the hits' mean colour
        image.at<cv::Vec4b>(v, u) = {ToByte(sum[2] * k), ToByte(sum[1] * k), ToByte(sum[0] * k),
                                     ToByte(float(hits) / (kSubsamples * kSubsamples))};
      }
    });
    const std::string name = "r_" + FrameName(view);
    WritePng(dir / "images" / (name + ".png"), image);
    nlohmann::json matrix = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) matrix.push_back({c2w(r, 0), c2w(r, 1), c2w(r, 2), c2w(r, 3)});
    frames.push_back({{"file_path", "./images/" + name}, {"transform_matrix", matrix}});
  }
  WriteText(dir / "transforms.json",
            nlohmann::json{{"camera_angle_x", kCameraAngleX}, {"frames", frames}}.dump(2));
  const nlohmann::json written = {{"object", true},         {"views", options.views},
                                  {"width", options.width}, {"height", options.height},
                                  {"seed", options.seed},   {"backdrop", options.backdrop}};
  WriteText(dir / "synth.json", written.dump(2) + "\n");
}

}  // namespace endorecon::scene
