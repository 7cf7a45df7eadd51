// Frames of a camera that turns about its centre, looking at a still, textured, distant surface
// (a turn moves every pixel by a homography, K R^T K^-1, whatever the depth), seen through a round
// scope: black outside a circle, as a laparoscope's frames are. For the mono recording's turns.
#pragma once

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace endorecon::testing {

struct TurningCamera {
  cv::Matx33d camera;              // the frames' pixel camera (f = 0.8898 W, centred)
  std::vector<cv::Matx33d> turns;  // camera-to-world per frame (OpenCV axes); [0] = identity
  std::vector<cv::Mat> frames;     // 8-bit BGR
};

// `turns_deg`: per frame after the first, its turn from the first as a rotation vector in degrees.
inline TurningCamera MakeTurningCamera(cv::Size size, const std::vector<cv::Vec3d>& turns_deg) {
  TurningCamera out;
  const double f = 0.8898 * size.width;
  out.camera = {f, 0, size.width / 2.0, 0, f, size.height / 2.0, 0, 0, 1};
  // The surface as the first camera would see it over twice its field: blobs at two scales, kept
  // below specular_mask.h's highlight level.
  const cv::Size canvas(2 * size.width, 2 * size.height);
  cv::RNG random(17);
  cv::Mat texture(canvas, CV_32FC3, cv::Scalar::all(0));
  for (int scale : {24, 6}) {
    cv::Mat coarse(canvas.height / scale, canvas.width / scale, CV_32FC3), fine;
    random.fill(coarse, cv::RNG::UNIFORM, 0.0, 1.0);
    cv::resize(coarse, fine, canvas, 0, 0, cv::INTER_CUBIC);
    texture += fine;
  }
  texture.convertTo(texture, CV_8UC3, 70, 10);
  const cv::Matx33d canvas_camera(f, 0, canvas.width / 2.0, 0, f, canvas.height / 2.0, 0, 0, 1);
  cv::Mat view(size, CV_8UC3, cv::Scalar::all(0));
  cv::circle(view, {size.width / 2, size.height / 2}, static_cast<int>(0.55 * size.width),
             cv::Scalar::all(255), cv::FILLED);
  out.turns.push_back(cv::Matx33d::eye());
  for (const cv::Vec3d& deg : turns_deg) {
    cv::Matx33d r;
    cv::Rodrigues(deg * (CV_PI / 180), r);
    out.turns.push_back(r);
  }
  for (const cv::Matx33d& turn : out.turns) {
    // A pixel's ray in this camera, in the world (the first camera), lands there on the canvas.
    const cv::Matx33d to_canvas = canvas_camera * turn * out.camera.inv();
    cv::Mat frame;
    cv::warpPerspective(texture, frame, cv::Mat(to_canvas), size, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP);
    cv::bitwise_and(frame, view, frame);
    out.frames.push_back(frame);
  }
  return out;
}

// The angle between two rotations, degrees.
inline double AngleBetweenDeg(const cv::Matx33d& a, const cv::Matx33d& b) {
  cv::Vec3d v;
  cv::Rodrigues(a.t() * b, v);
  return cv::norm(v) * 180 / CV_PI;
}

}  // namespace endorecon::testing
