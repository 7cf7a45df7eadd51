// What the token store takes from outside: bearer tokens from every call (TokenStore::Verify, against
// a store that holds one client token) and tenant names (ValidateTenant). The input is the token, a
// newline, then the tenant. Only the store's own token verifies; every other is UNAUTHENTICATED.
#include "server/token_store.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

using namespace endorecon;

struct Store {
  server::TokenStore tokens{fuzz::ScratchDir() / "tokens.sqlite"};
  std::string token = tokens.Create("fuzz", server::Role::kClient, "radiology");
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Store store;
  const std::string_view input = fuzz::Bytes(data, size);
  const auto newline = input.find('\n');
  const std::string token(input.substr(0, newline));
  const bool verified = fuzz::Accepts([&] { store.tokens.Verify(token); }, {ErrorCode::kUnauthenticated});
  if (verified != (token == store.token)) fuzz::Broken("a token verified that is not the store's own");
  if (newline != std::string_view::npos) {
    const std::string tenant(input.substr(newline + 1));
    fuzz::Accepts([&] { server::ValidateTenant(tenant); }, {ErrorCode::kInvalidArgument});
  }
  return 0;
}
