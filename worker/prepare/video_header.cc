#include "worker/prepare/video_header.h"

extern "C" {
#include <libavformat/avformat.h>
}

#include <algorithm>
#include <cmath>
#include <memory>

namespace endorecon::prepare {

VideoHeader ReadVideoHeader(const std::filesystem::path& file) {
  VideoHeader header;
  AVFormatContext* opened = nullptr;
  if (avformat_open_input(&opened, file.c_str(), nullptr, nullptr) < 0) return header;
  const auto close = [](AVFormatContext* context) { avformat_close_input(&context); };
  const std::unique_ptr<AVFormatContext, decltype(close)> context(opened, close);
  if (avformat_find_stream_info(context.get(), nullptr) < 0) return header;
  const int index = av_find_best_stream(context.get(), AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (index < 0) return header;
  const AVStream& stream = *context->streams[index];
  if (stream.nb_frames > 0) {
    header.frames = static_cast<int>(stream.nb_frames);
    return header;
  }
  const double rate = stream.avg_frame_rate.num > 0 && stream.avg_frame_rate.den > 0
                          ? av_q2d(stream.avg_frame_rate)
                          : av_q2d(stream.r_frame_rate);
  if (context->duration == AV_NOPTS_VALUE || !(rate > 0) || !std::isfinite(rate)) return header;
  // The container's duration counts from time zero where its timestamps start later (Matroska); where
  // it counts from the first timestamp (MPEG-TS), this announces fewer frames: a looser check only.
  const double start_s =
      stream.start_time != AV_NOPTS_VALUE ? double(stream.start_time) * av_q2d(stream.time_base) : 0.0;
  const double length_s = double(context->duration) / AV_TIME_BASE - std::max(0.0, start_s);
  if (length_s > 0) header.frames = static_cast<int>(std::lround(length_s * rate));
  return header;
}

}  // namespace endorecon::prepare
