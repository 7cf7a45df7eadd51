#include "worker/engine/scene/synthetic_scene.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "worker/engine/scene/portable_random.h"

namespace endorecon::scene {
namespace {

constexpr double kFocalPerWidth = 569.46820041 / 640.0;  // the EndoNeRF sample scenes' field of view
constexpr double kBaseDepth = 92;                        // tissue plane's z-depth before bumps and tilt
constexpr double kNear = 40, kFar = 130;
constexpr double kSquashCentre = 85, kStiffSquash = 0.08;
constexpr double kNearestTissue = 70, kDeepestTissue = 115;  // bounds the texture's resolution and extent
constexpr double kToolRadius = 4.0;
constexpr double kToolBaseDepth = 42, kToolTipDepth = 56;
constexpr double kPi = std::numbers::pi;

double Smoothstep(double lo, double hi, double x) {
  const double t = std::clamp((x - lo) / (hi - lo), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

std::array<float, 3> Mix(const std::array<float, 3>& a, const std::array<float, 3>& b, double w) {
  std::array<float, 3> out;
  for (int c = 0; c < 3; ++c) out[c] = static_cast<float>(a[c] + (b[c] - a[c]) * w);
  return out;
}

// Lattice hash to [0, 1): integer mixing, identical on every platform.
double Hash01(std::int64_t ix, std::int64_t iy, std::uint32_t salt) {
  std::uint32_t h = static_cast<std::uint32_t>(ix) * 0x8da6b343u ^
                    static_cast<std::uint32_t>(iy) * 0xd8163841u ^ salt * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h * 0x1.0p-32;
}

struct NoiseValue {
  double v, dx, dy;
};

// Gradient noise (Perlin's, quintic fade) with its analytic gradient, in about [-0.7, 0.7].
NoiseValue GradientNoise(double x, double y, std::uint32_t salt) {
  static constexpr double kDiagonal = 0.70710678118654752;
  static constexpr double kGradients[8][2] = {{1, 0},
                                              {-1, 0},
                                              {0, 1},
                                              {0, -1},
                                              {kDiagonal, kDiagonal},
                                              {-kDiagonal, kDiagonal},
                                              {kDiagonal, -kDiagonal},
                                              {-kDiagonal, -kDiagonal}};
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double tx = x - fx, ty = y - fy;
  const double ux = tx * tx * tx * (tx * (tx * 6 - 15) + 10), uy = ty * ty * ty * (ty * (ty * 6 - 15) + 10);
  const double dux = 30 * tx * tx * (tx - 1) * (tx - 1), duy = 30 * ty * ty * (ty - 1) * (ty - 1);
  const double* ga = kGradients[static_cast<int>(Hash01(ix, iy, salt) * 8)];
  const double* gb = kGradients[static_cast<int>(Hash01(ix + 1, iy, salt) * 8)];
  const double* gc = kGradients[static_cast<int>(Hash01(ix, iy + 1, salt) * 8)];
  const double* gd = kGradients[static_cast<int>(Hash01(ix + 1, iy + 1, salt) * 8)];
  const double va = ga[0] * tx + ga[1] * ty, vb = gb[0] * (tx - 1) + gb[1] * ty;
  const double vc = gc[0] * tx + gc[1] * (ty - 1), vd = gd[0] * (tx - 1) + gd[1] * (ty - 1);
  const double k = va - vb - vc + vd;
  NoiseValue n;
  n.v = va + ux * (vb - va) + uy * (vc - va) + ux * uy * k;
  n.dx = ga[0] + ux * (gb[0] - ga[0]) + uy * (gc[0] - ga[0]) + ux * uy * (ga[0] - gb[0] - gc[0] + gd[0]) +
         dux * (uy * k + vb - va);
  n.dy = ga[1] + ux * (gb[1] - ga[1]) + uy * (gc[1] - ga[1]) + ux * uy * (ga[1] - gb[1] - gc[1] + gd[1]) +
         duy * (ux * k + vc - va);
  return n;
}

// Fractal sum of `octaves` octaves of gradient noise, about [0, 1] around 0.5.
double Fbm(double x, double y, int octaves, std::uint32_t salt) {
  double sum = 0, weight = 0, amplitude = 1, scale = 1;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * GradientNoise(x * scale, y * scale, salt + 977u * o).v;
    weight += amplitude;
    amplitude *= 0.5;
    scale *= 2.03;
  }
  return 0.5 + sum / weight;
}

// Specular lobes cos^80 (wet tissue) and cos^24 (brushed metal), by squaring: std::pow is slow per pixel.
double TissueLobe(double c) {
  const double c2 = c * c, c4 = c2 * c2, c8 = c4 * c4, c16 = c8 * c8;
  return c16 * c16 * c16 * c16 * c16;
}
double ToolLobe(double c) {
  const double c2 = c * c, c4 = c2 * c2, c8 = c4 * c4;
  return c8 * c8 * c8;
}

// The tissue's texture at material point (x, y): mottled mucosa, fat, veins and capillaries (as
// {r, g, b} albedo), and the gradient {dx, dy} of a fine bump height field for the wet sheen.
std::array<float, 5> ProceduralTexel(double x, double y, std::uint32_t salt, bool dark) {
  static constexpr std::array<float, 3> kDark = {0.55f, 0.16f, 0.17f}, kPink = {0.80f, 0.38f, 0.34f};
  static constexpr std::array<float, 3> kFat = {0.86f, 0.70f, 0.42f};
  static constexpr std::array<float, 3> kVein = {0.38f, 0.05f, 0.09f}, kCapillary = {0.58f, 0.12f, 0.14f};
  std::array<float, 3> albedo = Mix(kDark, kPink, Smoothstep(0.3, 0.7, Fbm(x / 14, y / 14, 3, salt)));
  albedo = Mix(albedo, kFat, 0.55 * Smoothstep(0.62, 0.72, Fbm(x / 30, y / 30, 2, salt + 11)));
  const double wx = 10 * (Fbm(x / 20, y / 20, 2, salt + 23) - 0.5);
  const double wy = 10 * (Fbm(x / 20, y / 20, 2, salt + 37) - 0.5);
  const double vein = GradientNoise((x + wx) / 26, (y + wy) / 26, salt + 41).v;
  const double capillary = GradientNoise((x + 0.6 * wx) / 8, (y + 0.6 * wy) / 8, salt + 53).v;
  albedo = Mix(albedo, kVein, 0.85 * (1 - Smoothstep(0.015, 0.035, std::abs(vein))));
  albedo = Mix(albedo, kCapillary, 0.5 * (1 - Smoothstep(0.01, 0.025, std::abs(capillary))));
  if (dark) {
    for (float& c : albedo) c *= 0.05f;
  }
  constexpr double kBumpHeight = 0.2, kBumpScale = 2.2;
  const NoiseValue bump = GradientNoise(x / kBumpScale, y / kBumpScale, salt + 67);
  return {albedo[0], albedo[1], albedo[2], static_cast<float>(kBumpHeight / kBumpScale * bump.dx),
          static_cast<float>(kBumpHeight / kBumpScale * bump.dy)};
}

// First hit of the ray o + s d with the capsule of radius r around segment [a, b]; -1 if none.
double IntersectCapsule(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b, double r) {
  const Eigen::Vector3d ba = b - a, oa = o - a;
  const double baba = ba.dot(ba), bard = ba.dot(d), baoa = ba.dot(oa), rdoa = d.dot(oa), oaoa = oa.dot(oa);
  const double dd = d.dot(d);
  const double qa = baba * dd - bard * bard, qb = baba * rdoa - baoa * bard;
  const double qc = baba * oaoa - baoa * baoa - r * r * baba;
  double h = qb * qb - qa * qc;
  if (h < 0) return -1;
  const double s = (-qb - std::sqrt(h)) / qa;
  const double y = baoa + s * bard;
  if (y > 0 && y < baba) return s;
  const Eigen::Vector3d oc = y <= 0 ? oa : Eigen::Vector3d(o - b);
  const double sb = d.dot(oc), sc = oc.dot(oc) - r * r;
  h = sb * sb - dd * sc;
  return h > 0 ? (-sb - std::sqrt(h)) / dd : -1;
}

// Blinn-Phong with the light at the endoscope's tip and inverse-square falloff.
std::array<float, 3> Shade(const std::array<float, 3>& albedo, const Eigen::Vector3d& normal,
                           const Eigen::Vector3d& point, const Eigen::Vector3d& eye,
                           const Eigen::Vector3d& light, double ks, double (*lobe)(double), float* specular) {
  const Eigen::Vector3d to_light = light - point;
  const Eigen::Vector3d l = to_light.normalized(), v = (eye - point).normalized();
  const double diffuse = std::max(0.0, normal.dot(l));
  const double spec = ks * lobe(std::max(0.0, normal.dot((l + v).normalized())));
  const double falloff = kBaseDepth * kBaseDepth / to_light.squaredNorm();
  *specular = static_cast<float>(spec * falloff);
  std::array<float, 3> rgb;
  for (int c = 0; c < 3; ++c)
    rgb[c] = static_cast<float>((albedo[c] * (0.12 + 0.88 * diffuse) + spec) * falloff);
  return rgb;
}

}  // namespace

SyntheticScene::SyntheticScene(const SynthOptions& options)
    : options_(options), squash_(options.stiff ? kStiffSquash : 1.0) {
  PortableRandom random(options.seed);
  const double aspect = static_cast<double>(options.height) / options.width;
  const auto half_width_at = [](double depth) { return depth * 0.5 / kFocalPerWidth; };
  const double half_width = half_width_at(kBaseDepth), half_height = half_width * aspect;
  tilt_x_ = random.Uniform(-0.12, 0.12);
  tilt_y_ = random.Uniform(-0.12, 0.12);
  // A bump's steepest slope is 0.61 amplitude/sigma, at most 0.69 with breathing and pulling; even
  // two of them aligned with the tilt stay below 1.35, so along any ray of the field of view
  // (|direction.xy| < 0.73 for 5:4 frames) the depth changes slower than s and the ray meets the surface
  // once.
  for (int i = 0; i < kBumps; ++i) {
    State::Bump& bump = bumps_[i];
    bump.sigma = random.Uniform(12, 26);
    bump.amplitude = (i == kBumps - 1 ? 1 : -1) * random.Uniform(0.45, 0.65) * bump.sigma;
    bump.x = random.Uniform(-0.75, 0.75) * half_width;
    bump.y = random.Uniform(-0.75, 0.75) * half_height;
    breath_amount_[i] = random.Uniform(0.1, 0.25);
    breath_cycles_[i] = 1 + 0.5 * std::floor(random.Uniform(0, 3));
    breath_phase_[i] = random.Uniform(0, 2 * kPi);
  }
  const double pull_angle = random.Uniform(0, 2 * kPi), pull_length = random.Uniform(6, 9);
  pull_ = pull_length * Eigen::Vector2d(std::cos(pull_angle), std::sin(pull_angle));
  const double side = random.Uniform() < 0.5 ? 1 : -1;
  // Lateral positions follow the depth at which the tool is seen, so it enters from the image's edge
  // in stiff (squashed) scenes too.
  const double base_w = half_width_at(SeenDepth(kToolBaseDepth)),
               tip_w = half_width_at(SeenDepth(kToolTipDepth));
  tool_base_ = {side * 1.45 * base_w, random.Uniform(-0.6, -0.2) * base_w * aspect, -kToolBaseDepth};
  tool_start_ = {side * 0.45 * tip_w, random.Uniform(-0.3, 0.3) * tip_w * aspect, -kToolTipDepth};
  tool_end_ = {-side * 0.55 * tip_w, random.Uniform(-0.3, 0.3) * tip_w * aspect, -kToolTipDepth - 1};
  BuildAtlas(static_cast<std::uint32_t>(random.Uniform() * 4294967296.0), aspect);
}

void SyntheticScene::BuildAtlas(std::uint32_t salt, double aspect) {
  // The texture is sampled once, finer than a pixel of the nearest tissue, over everything either
  // eye can see (deepest tissue, plus the pull, the stereo baseline and the moving camera's reach);
  // rays read it bilinearly.
  const double margin = options_.moving ? 40 : 16, reach = kDeepestTissue * 0.5 / kFocalPerWidth;
  const double half_width = reach + margin, half_height = reach * aspect + margin;
  texel_ = kNearestTissue / (kFocalPerWidth * options_.width);
  atlas_width_ = static_cast<int>(std::ceil(2 * half_width / texel_)) + 2;
  atlas_height_ = static_cast<int>(std::ceil(2 * half_height / texel_)) + 2;
  atlas_x0_ = -half_width;
  atlas_y0_ = -half_height;
  atlas_.resize(static_cast<std::size_t>(atlas_width_) * atlas_height_);
  const bool picture = !options_.texture.empty();
  // A picture covers the atlas with its centre kept: one scale for both axes, the larger one cropped.
  const int tw = options_.texture_width, th = options_.texture_height;
  const double scale = picture ? std::min(double(tw) / atlas_width_, double(th) / atlas_height_) : 0;
  tbb::parallel_for(0, atlas_height_, [&](int row) {
    for (int column = 0; column < atlas_width_; ++column) {
      Texel& texel = atlas_[static_cast<std::size_t>(row) * atlas_width_ + column];
      texel = ProceduralTexel(atlas_x0_ + column * texel_, atlas_y0_ + row * texel_, salt, options_.stiff);
      if (!picture) continue;
      const double px = std::clamp(0.5 * tw + (column - 0.5 * atlas_width_) * scale, 0.0, tw - 1.001);
      const double py = std::clamp(0.5 * th + (row - 0.5 * atlas_height_) * scale, 0.0, th - 1.001);
      const int ix = int(px), iy = int(py);
      const double fx = px - ix, fy = py - iy;
      for (int c = 0; c < 3; ++c) {
        const auto at = [&](int x, int y) { return options_.texture[(std::size_t(y) * tw + x) * 3 + c] / 255.0; };
        const double top = at(ix, iy) + (at(ix + 1, iy) - at(ix, iy)) * fx;
        const double bottom = at(ix, iy + 1) + (at(ix + 1, iy + 1) - at(ix, iy + 1)) * fx;
        texel[c] = float((top + (bottom - top) * fy) * (options_.stiff ? 0.05 : 1.0));
      }
    }
  });
}

Camera SyntheticScene::LeftCamera() const {
  Camera camera;
  camera.width = options_.width;
  camera.height = options_.height;
  camera.fx = camera.fy = kFocalPerWidth * options_.width;
  camera.cx = options_.width / 2.0;
  camera.cy = options_.height / 2.0;
  return camera;
}

Eigen::Matrix<double, 3, 4> SyntheticScene::LeftPose(double t) const {
  Eigen::Matrix<double, 3, 4> pose = Eigen::Matrix<double, 3, 4>::Identity();
  if (!options_.moving) return pose;
  // Turned back towards the middle at both ends (rotation about y against the sideways offset), so
  // the tissue stays in view.
  const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(0.06 * t, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(0.05 * (2 * t - 1), Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(0.04 * std::sin(2 * kPi * t), Eigen::Vector3d::UnitX()))
                                       .toRotationMatrix();
  pose.leftCols<3>() = rotation;
  pose.col(3) = Eigen::Vector3d(6 * std::sin(kPi * (t - 0.5)), 3 * std::sin(2 * kPi * t), -5 * t);
  return pose;
}

double SyntheticScene::SeenDepth(double nominal) const {
  return kSquashCentre + squash_ * (nominal - kSquashCentre);
}
double SyntheticScene::near() const { return SeenDepth(kNear); }
double SyntheticScene::far() const { return SeenDepth(kFar); }

SyntheticScene::State SyntheticScene::At(double t) const {
  const double u = options_.static_scene ? 0.0 : t;
  // `motion` m > 1: a pull m times as long, back and forth (1 + m) / 2 times over the clip.
  const double cycles = options_.motion > 1 ? 0.5 * (1 + options_.motion) : 1.0;
  const Eigen::Vector2d reach = pull_ * options_.motion;
  const double pull = std::pow(std::sin(kPi * cycles * u), 2);
  State state;
  for (int i = 0; i < kBumps; ++i) {
    State::Bump bump = bumps_[i];
    bump.amplitude *= 1 + breath_amount_[i] * std::sin(2 * kPi * breath_cycles_[i] * u + breath_phase_[i]);
    if (i == 0) {
      bump.amplitude *= 1 + 0.4 * pull;
      bump.x += reach.x() * pull;
      bump.y += reach.y() * pull;
    }
    state.bumps[i] = bump;
  }
  state.pull = reach * pull;
  state.tool_base = tool_base_;
  state.tool_tip = tool_start_ + (tool_end_ - tool_start_) * u;
  state.tool_tip.y() += 3 * std::sin(2 * kPi * u);
  state.light = LeftPose(t).col(3);
  if (options_.motion > 1) {
    // The light circles the lens (at most 5 units off it) twice over the clip: the speculars move.
    const double radius = std::min(5.0, 2 * (options_.motion - 1)), angle = 4 * kPi * u;
    state.light += radius * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0);
  }
  if (options_.push) {
    // The tissue under the tool's tip pressed 3.5 units in, over a spot of sigma 7 (slope <= 0.31).
    state.dent = {state.tool_tip.x(), state.tool_tip.y(), 7.0, 3.5};
  }
  return state;
}

double SyntheticScene::TissueDepth(const State& state, double x, double y, double* dx, double* dy) const {
  double depth = kBaseDepth + tilt_x_ * x + tilt_y_ * y, gx = tilt_x_, gy = tilt_y_;
  const auto add = [&](const State::Bump& bump) {
    const double ex = x - bump.x, ey = y - bump.y, s2 = bump.sigma * bump.sigma;
    const double r2 = ex * ex + ey * ey;
    if (r2 > 36 * s2) return;  // exp(-18): below 1e-7 units
    const double g = bump.amplitude * std::exp(-r2 / (2 * s2));
    depth += g;
    gx -= g * ex / s2;
    gy -= g * ey / s2;
  };
  for (const State::Bump& bump : state.bumps) add(bump);
  if (state.dent.amplitude != 0) add(state.dent);
  *dx = squash_ * gx;
  *dy = squash_ * gy;
  return SeenDepth(depth);
}

std::array<float, 3> SyntheticScene::Albedo(const State& state, double x, double y, double* bump_dx,
                                            double* bump_dy) const {
  // Texture lives on the tissue: the pulled bump drags it along.
  const State::Bump& pulled = state.bumps[0];
  const double drag = std::exp(-((x - pulled.x) * (x - pulled.x) + (y - pulled.y) * (y - pulled.y)) /
                               (2 * pulled.sigma * pulled.sigma));
  const double gx = std::clamp((x - state.pull.x() * drag - atlas_x0_) / texel_, 0.0, atlas_width_ - 1.001);
  const double gy = std::clamp((y - state.pull.y() * drag - atlas_y0_) / texel_, 0.0, atlas_height_ - 1.001);
  const int ix = static_cast<int>(gx), iy = static_cast<int>(gy);
  const float fx = static_cast<float>(gx - ix), fy = static_cast<float>(gy - iy);
  const Texel* t00 = &atlas_[static_cast<std::size_t>(iy) * atlas_width_ + ix];
  const Texel* t10 = t00 + atlas_width_;
  Texel texel;
  for (std::size_t k = 0; k < texel.size(); ++k) {
    const float top = t00[0][k] + (t00[1][k] - t00[0][k]) * fx;
    const float bottom = t10[0][k] + (t10[1][k] - t10[0][k]) * fx;
    texel[k] = top + (bottom - top) * fy;
  }
  *bump_dx = texel[3];
  *bump_dy = texel[4];
  return {texel[0], texel[1], texel[2]};
}

SceneHit SyntheticScene::Trace(const State& state, const Eigen::Vector3d& origin,
                               const Eigen::Vector3d& direction, double depth_guess) const {
  // Tissue: solve s = D(origin.xy + s direction.xy) + origin.z by Newton's method (the surface is
  // z = -D); the slope bound makes the residual strictly increasing in s, so the root is unique.
  // Bisection on [near, far] (from the origin's plane) backs it up.
  const double z0 = origin.z();
  double s = depth_guess > near() + z0 && depth_guess < far() + z0 ? depth_guess : kSquashCentre + z0, gx = 0,
         gy = 0, depth = 0;
  bool converged = false;
  for (int iteration = 0; iteration < 30 && !converged; ++iteration) {
    depth = TissueDepth(state, origin.x() + s * direction.x(), origin.y() + s * direction.y(), &gx, &gy);
    const double step = (s - (depth + z0)) / (1 - (gx * direction.x() + gy * direction.y()));
    s -= step;
    converged = std::abs(step) < 1e-6;  // Newton: the error after this step is ~1e-12
  }
  if (!converged || !(s > near() + z0 && s < far() + z0)) {
    double lo = near() + z0, hi = far() + z0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      s = 0.5 * (lo + hi);
      depth = TissueDepth(state, origin.x() + s * direction.x(), origin.y() + s * direction.y(), &gx, &gy);
      (s < depth + z0 ? lo : hi) = s;
    }
  }
  const Eigen::Vector3d point = origin + s * direction;
  double bump_dx = 0, bump_dy = 0;
  const std::array<float, 3> albedo = Albedo(state, point.x(), point.y(), &bump_dx, &bump_dy);
  // The surface is z = -D(x, y): normal (D_x, D_y, 1); the fine bumps are not squashed.
  const Eigen::Vector3d normal = Eigen::Vector3d(gx + bump_dx, gy + bump_dy, 1).normalized();
  SceneHit hit;
  hit.tissue_depth = hit.depth = s;
  const double ks = options_.stiff ? 4.0 : 0.8;
  hit.tissue_rgb = hit.rgb = Shade(albedo, normal, point, origin, state.light, ks, TissueLobe, &hit.specular);
  if (!options_.tool) return hit;

  // Tool: intersect the capsule in unsquashed space (the ray parameter is unchanged by the affine map).
  const double centre_z = -kSquashCentre;
  const Eigen::Vector3d nominal_origin(origin.x(), origin.y(), centre_z + (origin.z() - centre_z) / squash_);
  const Eigen::Vector3d nominal_direction(direction.x(), direction.y(), direction.z() / squash_);
  const double s_tool =
      IntersectCapsule(nominal_origin, nominal_direction, state.tool_base, state.tool_tip, kToolRadius);
  if (s_tool <= 0 || s_tool >= s) return hit;
  const Eigen::Vector3d nominal_point = nominal_origin + s_tool * nominal_direction;
  const Eigen::Vector3d axis = state.tool_tip - state.tool_base;
  const double along = std::clamp((nominal_point - state.tool_base).dot(axis) / axis.squaredNorm(), 0.0, 1.0);
  Eigen::Vector3d normal_tool = (nominal_point - state.tool_base - along * axis) / kToolRadius;
  normal_tool.z() /= squash_;
  const float grey = along > 0.93 ? 0.08f : 0.22f;  // dark jaws at the tip
  hit.tool = true;
  hit.depth = s_tool;
  hit.rgb = Shade({grey, grey, grey * 1.04f}, normal_tool.normalized(), origin + s_tool * direction, origin,
                  state.light, 0.5, ToolLobe, &hit.specular);
  return hit;
}

SceneHit SyntheticScene::TraceAlong(const State& state, const Eigen::Vector3d& origin,
                                    const Eigen::Vector3d& direction, double depth_guess) const {
  // Trace solves for world z-depth; a direction of world z -1 makes the two the same (and the
  // identity camera's rays pass through unchanged, bit for bit).
  const double k = -direction.z();
  SceneHit hit = Trace(state, origin, direction / k, depth_guess * k);
  hit.depth /= k;
  hit.tissue_depth /= k;
  return hit;
}

}  // namespace endorecon::scene
