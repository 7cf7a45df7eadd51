// The include rules that keep the tree layered, as a check the tests run (layering_test.cc):
//  - the engine's folders in order, base -> scene -> field -> render -> {train, eval} -> cuda -> the
//    engine's top-level files (reconstruct and its stages): a file may include its own folder and the
//    folders before it, never one after it (train and eval stand side by side: neither includes the
//    other);
//  - the engine includes no gRPC and nothing of the service (server/, client/, worker/runtime/);
//  - client/ and server/ never include the engine (worker/), and common/ includes only common/ and what
//    its build generates (the protocol, endorecon/; endorecon_version.h).
// Only quoted includes of project paths are checked; system headers are the build's business.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace endorecon::layering {

struct Violation {
  std::string file;  // relative to the root, e.g. "worker/engine/field/mlp.cc"
  int line = 0;
  std::string include;  // what it includes
  std::string rule;     // which rule it breaks, in words
};

// Every violation in the C++ and CUDA sources under `root` (the repository's root), in path order.
std::vector<Violation> CheckIncludes(const std::filesystem::path& root);

std::string Describe(const Violation& violation);

}  // namespace endorecon::layering
