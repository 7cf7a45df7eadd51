#include "common/dicom/dataset_access.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "common/error.h"

namespace endorecon::dicom {

std::optional<std::string> FindString(DcmItem& item, const DcmTagKey& tag) {
  OFString value;
  if (item.findAndGetOFStringArray(tag, value).bad() || value.empty()) return std::nullopt;
  return std::string(value.c_str());
}

std::optional<long> FindInteger(DcmItem& item, const DcmTagKey& tag) {
  const auto number = FindNumber(item, tag);
  // Out of long's range (or not finite) the cast would be undefined: such a value is no integer here.
  if (!number || !(*number >= -9.2e18 && *number <= 9.2e18)) return std::nullopt;
  return static_cast<long>(*number);
}

std::optional<double> FindNumber(DcmItem& item, const DcmTagKey& tag, unsigned long index) {
  DcmElement* element = nullptr;
  if (item.findAndGetElement(tag, element).bad() || element == nullptr || element->getLength() == 0) {
    return std::nullopt;
  }
  OFString text;
  if (element->getOFString(text, index).bad() || text.empty()) return std::nullopt;
  try {
    std::size_t used = 0;
    const double value = std::stod(text.c_str(), &used);
    return value;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::vector<double> FindNumbers(DcmItem& item, const DcmTagKey& tag) {
  DcmElement* element = nullptr;
  std::vector<double> values;
  if (item.findAndGetElement(tag, element).bad() || element == nullptr) return values;
  for (unsigned long i = 0; i < element->getVM(); ++i) {
    const auto value = FindNumber(item, tag, i);
    if (!value) break;
    values.push_back(*value);
  }
  return values;
}

void Put(DcmItem& item, const DcmTagKey& tag, const std::string& value) {
  const OFCondition status = item.putAndInsertOFStringArray(tag, value.c_str());
  if (status.bad()) {
    Fail(ErrorCode::kInternal, "cannot set " + TagName(tag) + ": " + status.text());
  }
}

void PutUint16(DcmItem& item, const DcmTagKey& tag, Uint16 value) {
  const OFCondition status = item.putAndInsertUint16(tag, value);
  if (status.bad()) Fail(ErrorCode::kInternal, "cannot set " + TagName(tag) + ": " + status.text());
}

void PutTag(DcmItem& item, const DcmTagKey& tag, const DcmTagKey& value) {
  const OFCondition status = item.putAndInsertTagKey(tag, value);
  if (status.bad()) Fail(ErrorCode::kInternal, "cannot set " + TagName(tag) + ": " + status.text());
}

void PutEmpty(DcmItem& item, const DcmTagKey& tag) {
  const OFCondition status = item.insertEmptyElement(tag);
  if (status.bad()) Fail(ErrorCode::kInternal, "cannot add " + TagName(tag) + ": " + status.text());
}

std::string DecimalString(double value) {
  char text[32];
  for (const char* format : {"%.10g", "%.9e", "%.6e"}) {
    std::snprintf(text, sizeof(text), format, value);
    if (std::strlen(text) <= 16) break;
  }
  return text;
}

std::string FrameTimeVector(const std::vector<double>& times_s) {
  std::string vector = "0";
  for (std::size_t f = 1; f < times_s.size(); ++f) {
    vector += '\\';  // appended apart: GCC 12 warns falsely (-Wrestrict) on "\\" + string
    vector += DecimalString(1000.0 * std::max(0.0, times_s[f] - times_s[f - 1]));
  }
  return vector;
}

std::string TagName(const DcmTagKey& tag) {
  DcmTag named(tag);
  const char* name = named.getTagName();
  return name && *name ? name : tag.toString().c_str();
}

std::string UidName(const std::string& uid) {
  const char* name = dcmFindNameOfUID(uid.c_str(), nullptr);
  return name ? std::string(name) + " (" + uid + ")" : uid;
}

}  // namespace endorecon::dicom
