// The error-against-run-time plot (curve.svg in a results folder; the work-precision picture in
// the benchmarks): PSNR against seconds of training on a log time axis. Written as SVG by hand:
// Debian has no C++ plotting library, and the plot is a few lines, ticks and labels.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace endorecon::eval {

struct CurveSeries {
  std::string label;            // legend text, e.g. "held-out PSNR" or "cpu preset"
  std::vector<double> seconds;  // x, seconds of training; points with seconds <= 0 are left out (log axis)
  std::vector<double> psnr;     // y, dB, same length; NaN where a point has no value
  bool dashed = false;          // e.g. training PSNR beside the solid held-out line of a run
  std::string colour;           // SVG colour; empty picks one by the series' position
};

struct CurvePlotOptions {
  std::string title = "PSNR against training time";
  std::string y_label = "PSNR (dB)";
  std::string x_label = "training time (s, log scale)";
  int width = 760, height = 480;  // pixels
};

// Maps [lo, hi] (0 < lo < hi) onto pixels [p0, p1] logarithmically: every decade gets the same
// width. Values outside are extrapolated, not clamped.
class LogAxis {
 public:
  LogAxis(double lo, double hi, double p0, double p1);
  double operator()(double value) const;

 private:
  double log_lo_, scale_, p0_;
};

// The SVG document: x spans whole decades around the data (major ticks and grid at each decade,
// minor ticks at 2..9), y is linear with 1-2-5 steps; one polyline with point markers per series,
// and a legend. Series may be empty. Throws InvalidArgument when a series' seconds and psnr
// differ in length or the size is under 200 x 150.
std::string CurveSvg(std::span<const CurveSeries> series, const CurvePlotOptions& options = {});

// Writes CurveSvg to `path`; Error(kUnavailable) when it cannot be written.
void WriteCurveSvg(const std::filesystem::path& path, std::span<const CurveSeries> series,
                   const CurvePlotOptions& options = {});

}  // namespace endorecon::eval
