// The container recipes (deploy/containers/*.Dockerfile). No container engine runs here, so this
// checks what would make an image wrong: the build stage installs exactly what scripts/install-deps
// installs (it runs it), the runtime stage installs the runtime packages, those packages (with
// their dependencies) provide every shared library the built binaries load, and each image copies
// the binaries the manifests and units start.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <map>
#include <sstream>

#include "tests/deploy/deploy_files.h"
#include "tests/integration/sanitizer_build.h"

namespace endorecon::testing {
namespace fs = std::filesystem;
namespace {

struct Stage {
  std::string from;
  std::string text;  // its instructions, continuation lines joined
};

std::vector<Stage> StagesOf(const fs::path& recipe) {
  std::vector<Stage> stages;
  std::istringstream lines(ReadBytes(recipe));
  std::string line, instruction;
  while (std::getline(lines, line)) {
    const auto begin = line.find_first_not_of(' ');
    if (begin == std::string::npos || line[begin] == '#') continue;
    // A continued line and the next join with one space: "a \\" then "  && b" read "a && b".
    instruction += instruction.empty() ? line : line.substr(begin);
    if (instruction.back() == '\\') {
      instruction.pop_back();
      while (!instruction.empty() && instruction.back() == ' ') instruction.pop_back();
      instruction += ' ';
      continue;
    }
    if (instruction.rfind("FROM ", 0) == 0) stages.push_back({instruction.substr(5), ""});
    if (!stages.empty()) stages.back().text += instruction + "\n";
    instruction.clear();
  }
  return stages;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);)
    if (!line.empty()) lines.push_back(line);
  return lines;
}

TEST(ContainerRecipesTest, EachRecipeBuildsWithInstallDepsAndShipsTheRuntimePackages) {
  std::set<std::string> recipes;
  for (const auto& file : fs::directory_iterator(SourcePath("deploy/containers"))) {
    if (file.path().extension() != ".Dockerfile") continue;
    recipes.insert(file.path().stem().string());
    const auto stages = StagesOf(file.path());
    ASSERT_GE(stages.size(), 2u) << file.path();
    const Stage* build = nullptr;
    for (const auto& stage : stages)
      if (stage.from.ends_with(" AS build")) build = &stage;
    ASSERT_NE(build, nullptr) << file.path() << ": no build stage";
    EXPECT_EQ(build->from.rfind("debian:12", 0), 0u) << file.path() << ": builds on " << build->from;
    EXPECT_NE(build->text.find("COPY . /src"), std::string::npos) << file.path();
    EXPECT_NE(build->text.find("RUN /src/scripts/install-deps &&"), std::string::npos)
        << file.path() << ": the build stage must run scripts/install-deps (all of it)";
    const auto& runtime = stages.back();
    EXPECT_EQ(runtime.from, "debian:12-slim") << file.path();
    EXPECT_NE(runtime.text.find("COPY scripts/install-deps /usr/local/lib/endorecon/install-deps"),
              std::string::npos);
    // The server's image installs the server's libraries (no OpenCV), a worker's the worker's.
    const std::string image = file.path().stem().string() == "endorecon-server" ? "server" : "worker";
    EXPECT_NE(runtime.text.find("RUN /usr/local/lib/endorecon/install-deps --runtime " + image + " "),
              std::string::npos)
        << file.path() << ": expected install-deps --runtime " << image;
    EXPECT_NE(runtime.text.find("USER 10001"), std::string::npos) << file.path() << ": runs as root";
    // Every binary it copies is one the build stage builds.
    const std::regex copied("COPY --from=build /build/\\S+ /usr/local/bin/(\\S+)");
    int binaries = 0;
    for (auto it = std::sregex_iterator(runtime.text.begin(), runtime.text.end(), copied);
         it != std::sregex_iterator(); ++it, ++binaries) {
      EXPECT_NE(build->text.find(fmt::format(" {}", (*it)[1].str())), std::string::npos)
          << file.path() << " copies " << (*it)[1] << " but does not build it";
    }
    EXPECT_GT(binaries, 0) << file.path();
  }
  EXPECT_EQ(recipes,
            (std::set<std::string>{"endorecon-server", "endorecon-worker-cpu", "endorecon-worker-cuda"}));
  const auto cuda = ReadBytes(SourcePath("deploy/containers/endorecon-worker-cuda.Dockerfile"));
  EXPECT_NE(cuda.find("FROM nvidia/cuda:${CUDA_VERSION}-devel"), std::string::npos);
  EXPECT_NE(cuda.find("-DENDORECON_CUDA=ON"), std::string::npos);
}

// Each image's runtime packages and everything they depend on (the dpkg database of this machine,
// which install-deps set up from the same Debian 12 archive as the images) own every library its
// binary loads: the server's packages the server's and the CLI's, the worker's the worker's.
TEST(ContainerRecipesTest, RuntimePackagesProvideEveryLibraryTheBinariesLoad) {
  if (kAddressSanitizer || kThreadSanitizer)
    GTEST_SKIP() << "the images ship Release binaries; an instrumented build loads the sanitizer's runtime "
                    "(libatomic) too";
  std::map<std::string, std::vector<std::string>> depends;
  for (const auto& line : Lines(Capture("dpkg-query -W -f='${Package} ${Depends}, ${Pre-Depends}\\n'"))) {
    std::istringstream words(line);
    std::string package, word;
    words >> package;
    while (words >> word) {
      if (word.find_first_of("(),|") == 0 || word.find_first_of("<>=") != std::string::npos) continue;
      const auto clean = word.substr(0, word.find_first_of(",:"));
      if (!clean.empty() && std::isalnum(static_cast<unsigned char>(clean[0])))
        depends[package].push_back(clean);
    }
  }
  std::map<std::string, std::set<std::string>> closures;  // image -> packages with their dependencies
  for (const auto* image : {"server", "worker"}) {
    const auto runtime = Lines(
        Capture(fmt::format("'{}' --list-runtime {}", SourcePath("scripts/install-deps").string(), image)));
    ASSERT_FALSE(runtime.empty()) << image;
    for (const auto& package : runtime)
      EXPECT_TRUE(depends.count(package)) << package << " is not a Debian package here";
    std::vector<std::string> pending(runtime.begin(), runtime.end());
    while (!pending.empty()) {
      const auto package = pending.back();
      pending.pop_back();
      if (!closures[image].insert(package).second) continue;
      for (const auto& dependency : depends[package]) pending.push_back(dependency);
    }
  }
  EXPECT_FALSE(closures["server"].count("libopencv-core406")) << "the server's image brings OpenCV";
  // Each library ldd resolves, and the file it links to: with /usr merged, dpkg knows one of the two.
  std::map<std::string, std::vector<std::string>> libraries;  // binary -> libraries
  std::string paths;
  for (const auto* binary :
       {"server/endorecon-server", "worker/runtime/endorecon-worker", "client/endorecon"}) {
    libraries[binary] = Lines(Capture("ldd '" + BuiltBinary(binary) + "' | awk '/=> \\// {print $3}'"));
    ASSERT_FALSE(libraries[binary].empty()) << binary;
    for (const auto& library : libraries[binary])
      paths += " '" + library + "' '" + fs::canonical(library).string() + "'";
  }
  std::map<std::string, std::string> owners;  // path -> package
  for (const auto& line : Lines(Capture("dpkg -S" + paths + " 2>/dev/null"))) {
    const auto colon = line.find(": ");
    if (colon != std::string::npos) owners[line.substr(colon + 2)] = line.substr(0, line.find_first_of(":,"));
  }
  for (const auto& [binary, paths_of] : libraries) {
    for (const auto& library : paths_of) {
      const auto owner = owners.count(library) ? owners[library] : owners[fs::canonical(library).string()];
      ASSERT_FALSE(owner.empty()) << binary << " loads " << library << ", which no package owns";
      const std::string image = binary.starts_with("worker/") ? "worker" : "server";
      EXPECT_TRUE(closures[image].count(owner))
          << binary << " loads " << library << " from " << owner << ", which scripts/install-deps --runtime "
          << image << " does not bring";
    }
  }
}

TEST(ContainerRecipesTest, ImagesCopyTheBinariesTheUnitsAndScriptsStart) {
  const std::string server = ReadBytes(SourcePath("deploy/containers/endorecon-server.Dockerfile"));
  EXPECT_NE(server.find("/usr/local/bin/endorecon-server\n"), std::string::npos);
  for (const auto* worker : {"endorecon-worker-cpu", "endorecon-worker-cuda"}) {
    const std::string recipe =
        ReadBytes(SourcePath(std::string("deploy/containers/") + worker + ".Dockerfile"));
    EXPECT_NE(recipe.find("/usr/local/bin/endorecon-worker\n"), std::string::npos) << worker;
  }
  for (const auto* unit : {"endorecon-server.service", "endorecon-worker@.service"}) {
    const std::string text = ReadBytes(SourcePath(std::string("deploy/systemd/") + unit));
    const std::regex started("/usr/local/bin/(endorecon[a-z-]*)");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), started); it != std::sregex_iterator();
         ++it)
      EXPECT_FALSE(BinaryNamed((*it)[1]).empty()) << unit << " starts " << (*it)[1];
  }
}

}  // namespace
}  // namespace endorecon::testing
