// A job's recording options checked against a DICOM recording's headers, no pixel decoded: what the
// server checks when a recording is submitted (a --frames window past its end, a --size of another
// shape, a --stereo layout its series or frames do not fit, a file that is no recording), so that
// the submitter hears it at once, not after the queue; the worker meets the same checks as it reads
// the frames (recording.h).
#pragma once

#include <filesystem>
#include <string>

#include "common/dicom/recording_layout.h"
#include "common/prepare_flags.h"

namespace endorecon::dicom {

struct RecordingShape {
  int frames = 0;  // in the recording, before the window
  FrameSize eye;   // one eye's frame as recorded
};

// Throws what recording_series.h's loading and CheckSeriesFitLayout throw, and FailInvalid naming
// `path` for a window that holds none of the recording's frames and a `size` (empty: as recorded)
// that changes an eye's shape (CheckSameShape), and frames too large for a clip without one
// (CheckFrameFits).
RecordingShape CheckRecordingHeader(const std::filesystem::path& path, StereoLayout stereo,
                                    const FrameRange& window, FrameSize size);

// Throws FailInvalid naming `where` when `window` holds none of a recording's `frames`.
void CheckWindowHoldsFrames(const FrameRange& window, int frames, const std::string& where);

// Throws FailInvalid naming `where` when `size` is empty (frames as recorded) and `recorded` is larger
// than a clip's frame may be (kMostFramePixels), suggesting a --size of the same shape that fits.
void CheckFrameFits(FrameSize size, FrameSize recorded, const std::string& where);

// Throws FailInvalid when `size` (not empty) changes `recorded`'s aspect ratio by more than 1% (the
// clip's nominal focal length is per width), suggesting a size of the same shape.
void CheckSameShape(FrameSize size, FrameSize recorded);

}  // namespace endorecon::dicom
