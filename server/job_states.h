// What a job's state means to the server: finished, and whether DICOM sends are still to be tried
// (a SUCCEEDED job is settled only when none of its sends is PENDING or SENDING).
#pragma once

#include <algorithm>

#include "endorecon/v1/job.pb.h"

namespace endorecon::server {

inline bool Terminal(v1::JobState state) {
  return state == v1::SUCCEEDED || state == v1::FAILED || state == v1::CANCELLED;
}

// PENDING (waiting for an attempt) or SENDING (in one).
inline bool SendWaiting(const v1::DicomSend& send) {
  return send.state() == v1::DicomSend::PENDING || send.state() == v1::DicomSend::SENDING;
}

inline bool SendsWaiting(const v1::Job& job) {
  return std::any_of(job.sends().begin(), job.sends().end(), SendWaiting);
}

// Nothing more will happen to the job: it is finished and none of its DICOM sends is still
// waiting for an attempt or in one (a watch ends here).
inline bool Settled(const v1::Job& job) { return Terminal(job.state()) && !SendsWaiting(job); }

}  // namespace endorecon::server
