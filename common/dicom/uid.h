// New DICOM UIDs for the instances endorecon writes.
#pragma once

#include <string>

namespace endorecon::dicom {

// A new, unique UID. With an empty `root`: "2.25." and 128 random bits in decimal (a UUID-derived
// UID, ISO/IEC 9834-8, which needs no registered root). Otherwise `root` followed by DCMTK's
// unique suffix (host, process, time, counter). Throws InvalidArgument when `root` is not a valid
// UID prefix (digits and dots, no leading zeros, at most 40 characters, so 24 remain for the suffix).
std::string NewUid(const std::string& root);

// Throws InvalidArgument naming `what` unless `uid` is a valid UID (at most 64 characters, numeric
// components separated by dots, no leading zeros).
void CheckUid(const std::string& uid, const std::string& what);

}  // namespace endorecon::dicom
