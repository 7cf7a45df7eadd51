// dciodvfy (Debian's dicom3tools) as the judge of the DICOM files endorecon writes.
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace endorecon::testing {

// The lines of dciodvfy's report on `file` that start with "Error" (empty when it conforms;
// warnings are not counted). "dciodvfy did not run" when it could not be run.
inline std::string DciodvfyErrors(const std::filesystem::path& file) {
  const std::string command = "dciodvfy -new '" + file.string() + "' 2>&1; echo \"exit $?\"";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  std::string errors, last;
  char buffer[4096];
  while (pipe && fgets(buffer, sizeof(buffer), pipe.get())) {
    last = buffer;
    if (last.rfind("Error", 0) == 0) errors += last;
  }
  if (last.rfind("exit 127", 0) == 0) return "dciodvfy did not run (is dicom3tools installed?)";
  return errors;
}

}  // namespace endorecon::testing
