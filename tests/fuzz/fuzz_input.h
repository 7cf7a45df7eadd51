// What every libFuzzer harness shares: a scratch folder for inputs that readers take as files, and
// the contract each harness checks on every input. A reader of untrusted bytes either accepts them
// or throws endorecon::Error with one of the codes its header promises and a message naming the
// input; any other exception, an error with another code, a message that does not say where, or a
// sanitizer report is a finding (the harness aborts, libFuzzer saves the input).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

#include "common/error.h"

namespace endorecon::fuzz {

// A folder of this process's own, removed at exit (tmpfs when TMPDIR points at one).
const std::filesystem::path& ScratchDir();

// Writes `bytes` to ScratchDir()/`name` (mode 0600) and returns its path.
std::filesystem::path WriteInput(const std::string& name, std::string_view bytes);

inline std::string_view Bytes(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Prints what broke the contract and aborts (libFuzzer then saves the input as a crash).
[[noreturn]] void Broken(const std::string& what);

// Runs `read`. An endorecon::Error with one of `codes` whose message contains `where` (when not empty)
// is the reader refusing the input: returns false. Returns true when `read` accepted it. Anything else
// is Broken.
template <typename Read>
bool Accepts(Read&& read, std::initializer_list<ErrorCode> codes, std::string_view where = {}) {
  try {
    read();
    return true;
  } catch (const Error& e) {
    bool expected = false;
    for (const ErrorCode code : codes) expected = expected || code == e.code();
    if (!expected) Broken(std::string("unexpected error code ") + ErrorCodeName(e.code()) + ": " + e.what());
    if (std::string_view(e.what()).find(where) == std::string_view::npos)
      Broken("the error does not name '" + std::string(where) + "': " + e.what());
    return false;
  } catch (const std::exception& e) {
    Broken(std::string("an exception that is not endorecon::Error escaped: ") + e.what());
  }
}

}  // namespace endorecon::fuzz
