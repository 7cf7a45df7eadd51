// The analytic scene behind synthetic clips: a textured tissue height field that deforms smoothly
// over time (breathing bumps, one pulled sideways), seen by an endoscope (OpenGL camera at the
// origin looking down -z, light at the camera; with `moving`, the camera follows a known smooth
// path of a few degrees and some 20 units), and a grey capsule-shaped tool that sweeps across
// it. Rays are intersected exactly, so colour and z-depth are known truth. Units: tissue at z-depth
// ~60-105, tool ~42-58, near 40, far 130, so 8-bit depth PNGs hold them at one unit per level (a
// unit is about a millimetre). `stiff` squashes every depth towards 85 by a factor 0.08 (near 81.4,
// far 88.6, tissue ~84-86), darkens the tissue to near black and saturates the speculars.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "worker/engine/scene/camera.h"

namespace endorecon::scene {

struct SynthOptions {
  int frames = 48, width = 160, height = 128;
  std::uint64_t seed = 1;
  bool static_scene = false;  // nothing moves: tissue and tool as at time 0 (times still span [0, 1])
  bool tool = true;           // draw the tool and write masks/
  bool depth = true;          // write depth/
  bool stiff = false;         // thin depth range, near-opaque near-black tissue, saturated speculars
  bool stereo = false;        // also render the right eye (images_right/, stereo.json)
  bool moving = false;        // the endoscope moves (LeftPose); the tissue still deforms unless static_scene
  bool recording =
      false;  // also write recording/: the raw pair as a real rig records it (synthetic_recording.h)
  int checkerboard_views = 24;  // with `recording`: views of the calibration checkerboard (0: none)
  // Camera noise in images/ and images_right/ (CameraNoise in synthetic_frames.cc), its standard
  // deviation times this (0: none); gt/images is always noise-free, and so is recording/.
  double noise = 1;

  // What real recordings have and the default clip does not (issue 19), all off by default:
  // the tissue's albedo taken from a picture (e.g. a frame of a real recording: row-major RGB bytes,
  // stretched over the tissue, its centre kept where the aspects differ); the tissue's motion
  // scaled (`motion` times the pull, which drags the texture, in as many back-and-forth cycles as
  // it is over 1, and the light circling the endoscope's tip so the speculars move); the tissue
  // pressed in under the tool's tip (a dent that follows it); the exposure of each frame scaled by
  // 1 + flicker * u, u uniform in [-1, 1] (in gt/images too: it is the scene's light, not noise).
  std::vector<std::uint8_t> texture;
  int texture_width = 0, texture_height = 0;
  std::string texture_source;  // where the picture came from (synth.json)
  double motion = 1;
  bool push = false;
  double flicker = 0;
};

// Frame `index`'s time in [0, 1]: evenly spaced, 0 for a single frame.
inline double FrameTime(const SynthOptions& options, int index) {
  return options.frames == 1 ? 0.0 : static_cast<double>(index) / (options.frames - 1);
}

// What a ray sees. Colours are linear in [0, 1] before clamping (speculars may exceed 1).
struct SceneHit {
  double tissue_depth = 0;  // z-depth of the tissue (always hit)
  double depth = 0;         // z-depth of the first surface (tool or tissue)
  bool tool = false;        // the tool is in front of the tissue
  std::array<float, 3> tissue_rgb{};
  std::array<float, 3> rgb{};  // tool colour where `tool`, otherwise tissue_rgb
  float specular = 0;          // specular part of the first surface's shading
};

class SyntheticScene {
 public:
  static constexpr int kBumps = 5;

  // The scene's time-dependent state (see At).
  struct State {
    struct Bump {
      double x, y, sigma, amplitude;
    };
    std::array<Bump, kBumps> bumps;
    Eigen::Vector2d pull = Eigen::Vector2d::Zero();   // texture displacement of the pulled bump
    Eigen::Vector3d tool_base, tool_tip;              // capsule axis, undeformed (nominal) depths
    Eigen::Vector3d light = Eigen::Vector3d::Zero();  // the endoscope's tip (the left eye's centre)
    Bump dent{0, 0, 1, 0};                            // with `push`: under the tool's tip (amplitude 0: none)
  };

  // Draws the scene's parameters from options.seed; the image size fixes the field of view's aspect.
  explicit SyntheticScene(const SynthOptions& options);

  Camera LeftCamera() const;  // identity pose, f = 0.8898 W, cx = W/2, cy = H/2
  // The left eye's camera-to-world pose (OpenGL convention) at time t in [0, 1]: the identity, or
  // with `moving` a smooth path (x from -6 to 6, a sideways wiggle of 3, 5 units towards the tissue;
  // rotations of up to 2-3.5 degrees about each axis). It moves in static scenes too.
  Eigen::Matrix<double, 3, 4> LeftPose(double t) const;
  double near() const;
  double far() const;
  double baseline() const { return 5.0; }  // the right eye sits at (+baseline, 0, 0)

  // The state at time t in [0, 1] (as at 0 for a static scene).
  State At(double t) const;

  // Traces a ray from `origin` with direction `direction` (unit z-depth: direction.z() == -1);
  // depths are along it from the origin. `depth_guess` (e.g. the neighbouring pixel's tissue
  // depth) only speeds up the solve.
  SceneHit Trace(const State& state, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                 double depth_guess = 0) const;
  // The same for any direction looking into the scene (direction.z() < 0): depths (and the guess)
  // are in units of `direction`, the hit at origin + depth * direction. With a camera ray of unit
  // z-depth (Camera::Ray) they are the camera's z-depths, whatever its pose.
  SceneHit TraceAlong(const State& state, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                      double depth_guess = 0) const;

  // The tissue's z-depth under lateral position (x, y) (the surface is z = -depth), and its
  // gradient in *dx, *dy. Trace's tissue_depth s solves s = TissueDepth(origin.xy + s direction.xy)
  // + origin.z.
  double TissueDepth(const State& state, double x, double y, double* dx, double* dy) const;

 private:
  std::array<float, 3> Albedo(const State& state, double x, double y, double* bump_dx, double* bump_dy) const;
  void BuildAtlas(std::uint32_t salt, double aspect);
  double SeenDepth(double nominal) const;  // the squash: nominal z-depth -> rendered z-depth

  SynthOptions options_;
  double squash_;  // depth squash factor about kSquashCentre (1, or 0.08 when stiff)
  double tilt_x_, tilt_y_;
  std::array<State::Bump, kBumps> bumps_;
  std::array<double, kBumps> breath_amount_, breath_cycles_, breath_phase_;
  Eigen::Vector2d pull_;  // the pulled bump's (index 0) displacement at full pull
  Eigen::Vector3d tool_base_, tool_start_, tool_end_;
  // The tissue texture sampled on a grid in material coordinates: {r, g, b, bump dx, bump dy}.
  using Texel = std::array<float, 5>;
  std::vector<Texel> atlas_;
  int atlas_width_ = 0, atlas_height_ = 0;
  double atlas_x0_ = 0, atlas_y0_ = 0, texel_ = 1;
};

}  // namespace endorecon::scene
