// NumPy .npy files (depth maps, poses_bounds.npy) as ReadNpy reads them. An accepted array
// must hold exactly product(shape) values.
#include "common/npy.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  const auto path = fuzz::WriteInput("input.npy", fuzz::Bytes(data, size));
  NpyArray array;
  if (!fuzz::Accepts([&] { array = ReadNpy(path); }, {ErrorCode::kInvalidArgument}, path.string())) {
    return 0;
  }
  std::size_t count = 1;
  for (const std::size_t dim : array.shape) count *= dim;
  if (count != array.data.size()) fuzz::Broken("shape and value count disagree");
  return 0;
}
