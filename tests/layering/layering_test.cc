#include <gtest/gtest.h>

#include <fstream>

#include "tests/layering/include_rules.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::layering {
namespace {

namespace fs = std::filesystem;

void Write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

TEST(Layering, TheTreeKeepsItsIncludeRules) {
  const auto violations = CheckIncludes(ENDORECON_SOURCE_DIR);
  std::string report;
  for (const auto& v : violations) report += Describe(v) + "\n";
  EXPECT_TRUE(violations.empty()) << report;
}

// The check itself fails on the includes it exists to stop.
TEST(Layering, AnUpwardIncludeIsCaught) {
  testing::TempDir dir("layering");
  Write(dir / "worker/engine/field/mlp.cc",
        "#include \"worker/engine/base/counter_rng.h\"\n#include <vector>\n");
  Write(
      dir / "worker/engine/field/hash_grid.cc",
      "// uses a sampler\n#include \"worker/engine/field/mlp.h\"\n#include \"worker/engine/render/rng.h\"\n");
  Write(dir / "worker/engine/eval/curve.cc", "#include \"worker/engine/train/trainer.h\"\n");
  Write(dir / "worker/engine/scene/clip.cc", "#include <vector>\n#include <grpcpp/grpcpp.h>\n");
  Write(dir / "client/submit.cc", "#include \"worker/engine/reconstruct.h\"\n#include \"common/error.h\"\n");
  Write(dir / "server/main.cc", "#include \"endorecon/v1/job.pb.h\"\n#include \"server/store.h\"\n");
  Write(dir / "worker/engine/reconstruct.cc", "#include \"worker/engine/cuda/kernels.h\"\n");
  Write(dir / "common/dicom/stamp.cc", "#include \"endorecon_version.h\"\n#include \"common/error.h\"\n");
  const auto violations = CheckIncludes(dir.path());
  ASSERT_EQ(violations.size(), 4u);
  EXPECT_EQ(violations[0].file, "client/submit.cc");
  EXPECT_EQ(violations[1].file, "worker/engine/eval/curve.cc");
  EXPECT_EQ(violations[1].rule,
            "eval/ may not include train/ (order: base, scene, field, render, train|eval, cuda, top level)");
  EXPECT_EQ(violations[2].file, "worker/engine/field/hash_grid.cc");
  EXPECT_EQ(violations[2].line, 3);
  EXPECT_EQ(violations[2].include, "worker/engine/render/rng.h");
  EXPECT_EQ(violations[3].file, "worker/engine/scene/clip.cc");
  EXPECT_EQ(
      Describe(violations[2]),
      "worker/engine/field/hash_grid.cc:3 includes \"worker/engine/render/rng.h\": field/ may not include "
      "render/ (order: base, scene, field, render, train|eval, cuda, top level)");
}

}  // namespace
}  // namespace endorecon::layering
