#include "worker/prepare/opencv_storage.h"

#include <tinyxml2.h>
#include <yaml-cpp/yaml.h>

#include <cctype>
#include <charconv>
#include <fstream>
#include <sstream>

#include "common/error.h"
#include "common/file_read.h"

namespace endorecon::prepare {
namespace {

namespace fs = std::filesystem;

// An XML element's text split at white space; OpenCV quotes strings there ("3d").
std::vector<std::string> Words(const char* text) {
  std::vector<std::string> words;
  std::istringstream in(text ? text : "");
  for (std::string word; in >> word;) {
    if (word.size() >= 2 && word.front() == '"' && word.back() == '"') word = word.substr(1, word.size() - 2);
    words.push_back(word);
  }
  return words;
}

template <typename T>
bool ParseNumber(const std::string& text, T& value) {
  const char* end = text.data() + text.size();
  const auto [ptr, error] = std::from_chars(text.data(), end, value);
  return error == std::errc() && ptr == end;
}

}  // namespace

OpenCvStorage OpenCvStorage::Load(const fs::path& path) {
  const std::string name = path.string();
  RequireExistingFile(path, "calibration file");
  std::error_code error;
  const std::uintmax_t size = fs::file_size(path, error);
  if (error || size > kMaxBytes) {
    FailInvalid(name + ": " + std::to_string(size) + " bytes is too large for a calibration file (at most " +
                std::to_string(kMaxBytes) + ")");
  }
  std::ifstream in(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) Fail(ErrorCode::kUnavailable, name + ": cannot be read");
  std::size_t start = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  while (start < text.size() && std::isspace(static_cast<unsigned char>(text[start]))) ++start;
  return start < text.size() && text[start] == '<' ? ParseXml(text, name) : ParseYaml(text, name);
}

OpenCvStorage OpenCvStorage::ParseYaml(const std::string& text, const std::string& name) {
  // OpenCV writes "%YAML:1.0" first, which is no YAML directive yaml-cpp accepts: blank that line
  // (keeping line numbers in messages).
  std::string yaml = text;
  if (yaml.rfind("%YAML", 0) == 0) yaml.erase(0, std::min(yaml.find('\n'), yaml.size()));
  YAML::Node top;
  try {
    top = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    FailInvalid(name + ": not valid YAML or XML (" + e.what() + ")");
  }
  if (!top.IsMap()) FailInvalid(name + ": not an OpenCV storage file (its top level is no map of fields)");
  OpenCvStorage storage;
  storage.name_ = name;
  const auto scalars = [](const YAML::Node& list, std::vector<std::string>& words) {
    for (const YAML::Node& item : list) {
      if (!item.IsScalar()) {
        words.clear();
        return;
      }
      words.push_back(item.Scalar());
    }
  };
  for (const auto& pair : top) {
    if (!pair.first.IsScalar()) continue;
    const YAML::Node& value = pair.second;
    Field field;
    if (value.IsScalar()) {
      field.words = {value.Scalar()};
    } else if (value.IsSequence()) {
      scalars(value, field.words);
    } else if (value.IsMap() && value["rows"] && value["cols"] && value["data"]) {
      field.matrix = true;
      const auto text_of = [&](const char* key) {
        const YAML::Node node = value[key];
        return node && node.IsScalar() ? node.Scalar() : std::string();
      };
      field.rows = text_of("rows");
      field.cols = text_of("cols");
      field.dt = text_of("dt");
      if (value["data"].IsSequence()) scalars(value["data"], field.words);
    }
    storage.fields_.emplace(pair.first.Scalar(), std::move(field));
  }
  return storage;
}

OpenCvStorage OpenCvStorage::ParseXml(const std::string& text, const std::string& name) {
  tinyxml2::XMLDocument document;
  if (document.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS)
    FailInvalid(name + ": not well-formed XML (" + document.ErrorStr() + ")");
  const tinyxml2::XMLElement* root = document.RootElement();
  if (!root || std::string(root->Name()) != "opencv_storage")
    FailInvalid(name + ": not an OpenCV storage file (its XML root is not <opencv_storage>)");
  OpenCvStorage storage;
  storage.name_ = name;
  for (const tinyxml2::XMLElement* element = root->FirstChildElement(); element;
       element = element->NextSiblingElement()) {
    Field field;
    const auto text_of = [&](const char* key) {
      const tinyxml2::XMLElement* child = element->FirstChildElement(key);
      const std::vector<std::string> words = Words(child ? child->GetText() : nullptr);
      return words.size() == 1 ? words[0] : std::string();
    };
    if (!element->FirstChildElement()) {
      field.words = Words(element->GetText());
    } else if (element->FirstChildElement("rows") && element->FirstChildElement("cols") &&
               element->FirstChildElement("data")) {
      field.matrix = true;
      field.rows = text_of("rows");
      field.cols = text_of("cols");
      field.dt = text_of("dt");
      field.words = Words(element->FirstChildElement("data")->GetText());
    }
    storage.fields_.emplace(element->Name(), std::move(field));
  }
  return storage;
}

std::optional<cv::Mat> OpenCvStorage::Matrix(const std::string& key) const {
  const auto found = fields_.find(key);
  if (found == fields_.end()) return std::nullopt;
  const Field& field = found->second;
  const std::string where = name_ + ": '" + key + "'";
  if (!field.matrix) FailInvalid(where + " is not a matrix (expected an opencv-matrix)");
  // No calibration matrix is larger than 16 x 16; OpenCV allocated whatever size a file declared
  // (tests/fuzz/stereo_calibration_fuzz.cc found 10^9 rows).
  int rows = 0, cols = 0;
  if (!ParseNumber(field.rows, rows) || !ParseNumber(field.cols, cols) || rows < 1 || rows > 16 || cols < 1 ||
      cols > 16) {
    FailInvalid(where + " must declare rows and cols between 1 and 16");
  }
  // dt: an optional channel count and OpenCV's element type letter (u c w s i f d h).
  int channels = 1;
  const std::string& dt = field.dt;
  const bool counted = dt.size() == 2 && dt[0] >= '1' && dt[0] <= '4';
  if (counted) channels = dt[0] - '0';
  if (dt.size() != (counted ? 2u : 1u) || std::string("ucwsifdh").find(dt.back()) == std::string::npos)
    FailInvalid(where + " has dt '" + dt + "', which is no OpenCV element type (e.g. d, f, 3d)");
  const std::size_t count = static_cast<std::size_t>(rows) * cols * channels;
  if (field.words.size() != count) {
    FailInvalid(where + " declares " + std::to_string(rows) + "x" + std::to_string(cols) + " (" + dt +
                ") but its data holds " + std::to_string(field.words.size()) + " numbers");
  }
  cv::Mat m(rows, cols * channels, CV_64F);
  for (std::size_t i = 0; i < count; ++i) {
    if (!ParseNumber(field.words[i], m.ptr<double>()[i]))
      FailInvalid(where + " entry " + std::to_string(i) + " ('" + field.words[i] + "') is not a number");
  }
  return m;
}

std::optional<std::vector<int>> OpenCvStorage::Ints(const std::string& key) const {
  const auto found = fields_.find(key);
  if (found == fields_.end()) return std::nullopt;
  const Field& field = found->second;
  std::vector<int> values(field.words.size());
  bool ok = !field.matrix && !values.empty();
  for (std::size_t i = 0; ok && i < values.size(); ++i) ok = ParseNumber(field.words[i], values[i]);
  if (!ok) FailInvalid(name_ + ": '" + key + "' must be whole numbers");
  return values;
}

}  // namespace endorecon::prepare
