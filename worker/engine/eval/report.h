// report.html: the one page of a results folder a person looks at (docs/formats.md, "report.html"):
// every frame (input, rendered, depth, uncertainty, error, tool pixels shaded, held-out frames marked),
// the 3D surface, the error against run time, per-frame metrics, the calibration curves, what was
// left out, the configuration, the machine, the device, the time and the version. Self-contained:
// images and data are inside the file, nothing is fetched.
#pragma once

#include <filesystem>

namespace endorecon::scene {
struct Clip;
}

namespace endorecon::eval {

// Writes results_dir/report.html from what the folder holds (and returns its path):
// - a reconstruction's results (metrics.json, config.json, rgb/, depth/*.npy, uncertainty/, error/),
//   with `clip`, the run's loaded clip (the pixels its evaluation left out shaded: tool masks, and the
//   area outside a scope's view where left out), or without one the clip that config.json names
//   ("clip") read again, for its images, evaluation masks, cameras and times (read again beside the
//   run's, it doubled the run's peak memory for its frames);
// - or a render's views (render.json, cameras.json, rgb/, depth/*.npy, uncertainty/).
// Frames wider than 480 pixels are downscaled for the page; the 3D surface samples every frame's depth
// on a grid sized to at most 600,000 points in all. Without rendered frames (a cancelled run) the page
// shows the rest. Throws Error(kInvalidArgument) naming the file when the folder holds neither
// metrics.json nor render.json or a file it needs is missing or malformed, the clip loader's errors
// when the clip cannot be read, Error(kUnavailable) when report.html cannot be written.
std::filesystem::path WriteReport(const std::filesystem::path& results_dir,
                                  const scene::Clip* clip = nullptr);

}  // namespace endorecon::eval
