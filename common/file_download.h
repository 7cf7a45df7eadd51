// The receiving side of a download (the CLI's results, the worker's clips and checkpoints): each
// file lands in <dir>/<path>.part, is verified against its SHA-256 and only then renamed into
// place, so an interrupted download resumes from the .part's size and never leaves a wrong file.
#pragma once

#include <grpcpp/support/sync_stream.h>

#include <cstdint>
#include <filesystem>
#include <vector>

#include "endorecon/v1/files.pb.h"

namespace endorecon {

// The files of `manifest` still missing from `dir` (absent, or present with another size or
// digest), each with the offset its .part file reached. Sets path, sha256 and offset.
std::vector<v1::FileRange> PendingDownloads(const std::filesystem::path& dir, const v1::Manifest& manifest);

// The ranges of `pending` whose content no earlier one asks for: a content under several names (the
// identical masks of frames without a tool) is downloaded once, then copied by CopyDuplicates.
std::vector<v1::FileRange> OnePerContent(const std::vector<v1::FileRange>& pending);
// After OnePerContent(pending) was received into `dir`: makes each other range of `pending` a copy of
// the received file of its content (replacing what is there), and removes its .part. Throws
// Error naming the file when a copy cannot be written: kResourceExhausted for a full disk (as a
// received file's write), else kInternal.
void CopyDuplicates(const std::filesystem::path& dir, const std::vector<v1::FileRange>& pending);

// Writes a FileChunk stream into `dir`; returns the bytes written. Throws Error(kDataLoss) when a
// file's digest does not match (its .part is removed), kInvalidArgument for an unsafe path or an
// out-of-order chunk. Checks the stream's status itself.
std::int64_t ReceiveFiles(grpc::ClientReaderInterface<v1::FileChunk>& reader,
                          const std::filesystem::path& dir);

// Writes what the filesystem holding `dir` has in memory to its disk (syncfs): the files received
// are there after a power cut. Throws Error(kUnavailable) naming `dir` when it cannot.
void SyncFolder(const std::filesystem::path& dir);

}  // namespace endorecon
