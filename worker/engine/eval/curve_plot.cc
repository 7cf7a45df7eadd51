#include "worker/engine/eval/curve_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "common/error.h"
#include "common/file_write.h"
#include "worker/engine/eval/markup_text.h"

namespace endorecon::eval {
namespace {

// Okabe-Ito: distinguishable with the common colour-vision deficiencies.
constexpr const char* kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                    "#E69F00", "#56B4E9", "#000000", "#F0E442"};
constexpr double kLeft = 64, kRight = 20, kTop = 36, kBottom = 52;

std::string Num(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", value);
  return text;
}

std::string TickLabel(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

bool Plotted(const CurveSeries& s, std::size_t i) {
  return s.seconds[i] > 0 && std::isfinite(s.seconds[i]) && std::isfinite(s.psnr[i]);
}

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  bool empty() const { return lo > hi; }
};

// Whole decades around [lo, hi]; 1 s to 10 s when there is no data.
Range DecadeRange(Range data) {
  if (data.empty()) return {1, 10};
  Range r{std::pow(10.0, std::floor(std::log10(data.lo))), std::pow(10.0, std::ceil(std::log10(data.hi)))};
  if (r.hi <= r.lo) r.hi = r.lo * 10;
  return r;
}

// A 1-2-5 step giving about six intervals over `data`, and the range widened to whole steps.
Range NiceRange(Range data, double& step) {
  if (data.empty()) data = {0, 40};
  if (data.hi - data.lo < 1e-9) data = {data.lo - 1, data.hi + 1};
  const double raw = (data.hi - data.lo) / 6;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  step = decade * (raw <= decade ? 1 : raw <= 2 * decade ? 2 : raw <= 5 * decade ? 5 : 10);
  return {std::floor(data.lo / step) * step, std::ceil(data.hi / step) * step};
}

}  // namespace

LogAxis::LogAxis(double lo, double hi, double p0, double p1)
    : log_lo_(std::log10(lo)), scale_((p1 - p0) / (std::log10(hi) - std::log10(lo))), p0_(p0) {
  if (!(lo > 0 && hi > lo))
    FailInvalid("log axis: range [" + std::to_string(lo) + ", " + std::to_string(hi) +
                "] is not 0 < lo < hi");
}

double LogAxis::operator()(double value) const { return p0_ + (std::log10(value) - log_lo_) * scale_; }

std::string CurveSvg(std::span<const CurveSeries> series, const CurvePlotOptions& options) {
  if (options.width < 200 || options.height < 150) {
    FailInvalid("curve plot: size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                " is under 200x150");
  }
  Range xs, ys;
  for (const CurveSeries& s : series) {
    if (s.seconds.size() != s.psnr.size()) {
      FailInvalid("curve plot: series '" + s.label + "' has " + std::to_string(s.seconds.size()) +
                  " times and " + std::to_string(s.psnr.size()) + " PSNR values");
    }
    for (std::size_t i = 0; i < s.seconds.size(); ++i) {
      if (!Plotted(s, i)) continue;
      xs = {std::min(xs.lo, s.seconds[i]), std::max(xs.hi, s.seconds[i])};
      ys = {std::min(ys.lo, s.psnr[i]), std::max(ys.hi, s.psnr[i])};
    }
  }
  const double w = options.width, h = options.height;
  const double x0 = kLeft, x1 = w - kRight, y0 = h - kBottom, y1 = kTop;  // y0 is the bottom
  const Range xr = DecadeRange(xs);
  double y_step = 1;
  const Range yr = NiceRange(ys, y_step);
  const LogAxis x_axis(xr.lo, xr.hi, x0, x1);
  const auto y_axis = [&](double v) { return y0 + (v - yr.lo) / (yr.hi - yr.lo) * (y1 - y0); };

  std::ostringstream svg;
  svg << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << options.width << "\" height=\""
      << options.height << "\" viewBox=\"0 0 " << options.width << " " << options.height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << Num(w / 2) << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">"
      << EscapeMarkup(options.title) << "</text>\n";

  svg << "<g class=\"x-axis\" stroke=\"#000\">\n";
  for (double decade = xr.lo; decade <= xr.hi * 1.0001; decade *= 10) {
    const double x = x_axis(decade);
    svg << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(y1) << "\" x2=\"" << Num(x) << "\" y2=\"" << Num(y0)
        << "\" stroke=\"#ddd\"/>\n"
        << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(y0) << "\" x2=\"" << Num(x) << "\" y2=\""
        << Num(y0 + 6) << "\"/>\n"
        << "<text x=\"" << Num(x) << "\" y=\"" << Num(y0 + 20) << "\" text-anchor=\"middle\" stroke=\"none\">"
        << TickLabel(decade) << "</text>\n";
    for (int m = 2; m <= 9 && decade * m < xr.hi; ++m) {
      const double xm = x_axis(decade * m);
      svg << "<line x1=\"" << Num(xm) << "\" y1=\"" << Num(y0) << "\" x2=\"" << Num(xm) << "\" y2=\""
          << Num(y0 + 3) << "\"/>\n";
    }
  }
  svg << "</g>\n<g class=\"y-axis\" stroke=\"#000\">\n";
  for (double v = yr.lo; v <= yr.hi + y_step * 1e-6; v += y_step) {
    const double y = y_axis(v);
    svg << "<line x1=\"" << Num(x0) << "\" y1=\"" << Num(y) << "\" x2=\"" << Num(x1) << "\" y2=\"" << Num(y)
        << "\" stroke=\"#ddd\"/>\n"
        << "<line x1=\"" << Num(x0 - 6) << "\" y1=\"" << Num(y) << "\" x2=\"" << Num(x0) << "\" y2=\""
        << Num(y) << "\"/>\n"
        << "<text x=\"" << Num(x0 - 9) << "\" y=\"" << Num(y + 4) << "\" text-anchor=\"end\" stroke=\"none\">"
        << TickLabel(std::round(v / y_step) * y_step) << "</text>\n";
  }
  svg << "</g>\n"
      << "<rect x=\"" << Num(x0) << "\" y=\"" << Num(y1) << "\" width=\"" << Num(x1 - x0) << "\" height=\""
      << Num(y0 - y1) << "\" fill=\"none\" stroke=\"#000\"/>\n"
      << "<text x=\"" << Num((x0 + x1) / 2) << "\" y=\"" << Num(h - 12) << "\" text-anchor=\"middle\">"
      << EscapeMarkup(options.x_label) << "</text>\n"
      << "<text x=\"16\" y=\"" << Num((y0 + y1) / 2) << "\" text-anchor=\"middle\" transform=\"rotate(-90 16 "
      << Num((y0 + y1) / 2) << ")\">" << EscapeMarkup(options.y_label) << "</text>\n";

  const auto colour_of = [&](std::size_t k) {
    return series[k].colour.empty() ? std::string(kPalette[k % std::size(kPalette)]) : series[k].colour;
  };
  const auto dash_of = [&](std::size_t k) { return series[k].dashed ? " stroke-dasharray=\"6 4\"" : ""; };
  for (std::size_t k = 0; k < series.size(); ++k) {
    const CurveSeries& s = series[k];
    std::ostringstream points, markers;
    for (std::size_t i = 0; i < s.seconds.size(); ++i) {
      if (!Plotted(s, i)) continue;
      const double x = x_axis(s.seconds[i]), y = y_axis(s.psnr[i]);
      points << (points.tellp() > 0 ? " " : "") << Num(x) << "," << Num(y);
      markers << "<circle cx=\"" << Num(x) << "\" cy=\"" << Num(y) << "\" r=\"2.5\"/>\n";
    }
    svg << "<g class=\"series\" fill=\"" << colour_of(k) << "\">\n<polyline fill=\"none\" stroke=\""
        << colour_of(k) << "\" stroke-width=\"2\"" << dash_of(k) << " points=\"" << points.str() << "\"/>\n"
        << markers.str() << "</g>\n";
  }
  if (!series.empty()) {  // bottom right, where PSNR-against-time curves rarely are
    const double top = y0 - 8 - 18.0 * series.size();
    svg << "<g class=\"legend\">\n<rect x=\"" << Num(x1 - 198) << "\" y=\"" << Num(top)
        << "\" width=\"192\" height=\"" << Num(18.0 * series.size() + 4)
        << "\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#999\"/>\n";
    for (std::size_t k = 0; k < series.size(); ++k) {
      const double ly = top + 11 + 18.0 * k;
      svg << "<line x1=\"" << Num(x1 - 190) << "\" y1=\"" << Num(ly) << "\" x2=\"" << Num(x1 - 160)
          << "\" y2=\"" << Num(ly) << "\" stroke=\"" << colour_of(k) << "\" stroke-width=\"2\"" << dash_of(k)
          << "/>\n"
          << "<text x=\"" << Num(x1 - 154) << "\" y=\"" << Num(ly + 4) << "\">"
          << EscapeMarkup(series[k].label) << "</text>\n";
    }
    svg << "</g>\n";
  }
  svg << "</svg>\n";
  return svg.str();
}

void WriteCurveSvg(const std::filesystem::path& path, std::span<const CurveSeries> series,
                   const CurvePlotOptions& options) {
  WriteFile(path, CurveSvg(series, options), "curve plot");
}

}  // namespace endorecon::eval
