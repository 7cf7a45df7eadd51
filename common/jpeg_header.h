// A JPEG stream's header, walked by the standard's rules (ITU-T T.81 B.1.1): from after its SOI
// marker, length-prefixed marker segments and fill bytes. One walk for the two checks that read it:
// a truncated JPEG frame of a clip (image_bytes.cc) and a DICOM recording's JPEG frames, whose
// malformed headers DCMTK would not return from (dicom/recording.cc).
#pragma once

#include <cstddef>
#include <optional>

namespace endorecon {

// The offset of the first marker (its 0xFF) in the header of the JPEG stream `data` for which
// `stop(marker)` holds, its length bytes within `size`; none when the walk cannot go on first: a byte
// that is no marker, a stand-alone marker (TEM, RSTn, SOI, EOI) or a stuffed zero, a segment length
// under 2, or the end of the data.
std::optional<std::size_t> FindJpegHeaderMarker(const unsigned char* data, std::size_t size,
                                                bool (*stop)(unsigned char marker));

}  // namespace endorecon
