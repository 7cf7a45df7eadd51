// Reading and writing single attributes of a DCMTK dataset with errors that name the attribute
// (by its dictionary name) and the file. Internal to common/dicom.
#pragma once

#include <dcmtk/dcmdata/dctk.h>

#include <optional>
#include <string>
#include <vector>

namespace endorecon::dicom {

// The attribute's whole value (all components, backslash-separated), or nullopt when absent or empty.
std::optional<std::string> FindString(DcmItem& item, const DcmTagKey& tag);
// The attribute as an integer, nullopt when absent, empty or not a number.
std::optional<long> FindInteger(DcmItem& item, const DcmTagKey& tag);
// Component `index` of a numeric (DS, IS, US) attribute, nullopt when absent.
std::optional<double> FindNumber(DcmItem& item, const DcmTagKey& tag, unsigned long index = 0);
// Components of a multi-valued numeric attribute; empty when absent.
std::vector<double> FindNumbers(DcmItem& item, const DcmTagKey& tag);

// Inserts or replaces the attribute. Throws Error(kInternal) naming the attribute when DCMTK refuses
// the value (a bug in the caller: a value of the wrong form).
void Put(DcmItem& item, const DcmTagKey& tag, const std::string& value);
void PutUint16(DcmItem& item, const DcmTagKey& tag, Uint16 value);
// An attribute tag value (VR AT), e.g. Frame Increment Pointer -> Frame Time.
void PutTag(DcmItem& item, const DcmTagKey& tag, const DcmTagKey& value);
// An empty attribute (a type 2 sequence, say).
void PutEmpty(DcmItem& item, const DcmTagKey& tag);

// A Decimal String (DS) value of at most 16 characters.
std::string DecimalString(double value);
// A Frame Time Vector (0018,1065) value: "0", then the milliseconds between consecutive times
// (seconds, negative steps written as 0), backslash-separated.
std::string FrameTimeVector(const std::vector<double>& times_s);

// The dictionary name of a tag ("NumberOfFrames"), for messages.
std::string TagName(const DcmTagKey& tag);
// "Video Endoscopic Image Storage (1.2.840.10008.5.1.4.1.1.77.1.1.1)" for a known UID, else the UID.
std::string UidName(const std::string& uid);

}  // namespace endorecon::dicom
