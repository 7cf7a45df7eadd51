// Names that arrive from the network (upload manifests, result manifests) become paths on disk
// only after this check, so no peer can write or read outside the folder it was given.
#pragma once

#include <string_view>

namespace endorecon {

// Throws Error(kInvalidArgument) naming `path` unless it is relative and '/'-separated, with no
// empty, "." or ".." segments, no backslash, no NUL and at most 4096 bytes.
void CheckRelativePath(std::string_view path);

// Whether `text` is well-formed UTF-8 (RFC 3629: no overlong forms, no surrogates, nothing past
// U+10FFFF), as protobuf's strings must be.
bool IsUtf8(std::string_view text);

}  // namespace endorecon
