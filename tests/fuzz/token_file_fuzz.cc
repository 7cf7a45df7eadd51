// Token files (`--token-file` of the CLI and the worker) as ReadTokenFile reads them. An accepted file
// yields one non-empty word; a malformed token is UNAUTHENTICATED, as the server's refusal of one.
#include "common/transport_security.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  const auto path = fuzz::WriteInput("token", fuzz::Bytes(data, size));
  std::string token;
  if (!fuzz::Accepts([&] { token = ReadTokenFile(path, "--token-file"); },
                     {ErrorCode::kInvalidArgument, ErrorCode::kNotFound, ErrorCode::kUnauthenticated},
                     path.string())) {
    return 0;
  }
  if (token.empty() || token.find_first_of(" \t\r\n") != std::string::npos)
    fuzz::Broken("accepted a token that is not one word");
  return 0;
}
