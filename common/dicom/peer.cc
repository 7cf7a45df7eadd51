#include "common/dicom/peer.h"

#include "common/error.h"

namespace endorecon::dicom {

void CheckAeTitle(const std::string& ae_title, const std::string& what) {
  bool printable = !ae_title.empty() && ae_title.size() <= 16 && ae_title.front() != ' ';
  for (const char c : ae_title) printable = printable && c >= 0x20 && c < 0x7f && c != '\\';
  if (!printable) {
    FailInvalid(what + " '" + ae_title +
                "' is not an AE title (1 to 16 printable ASCII characters, no backslash)");
  }
}

Peer ParsePeer(const std::string& text) {
  const auto at = text.find('@');
  const auto colon = text.rfind(':');
  if (at == std::string::npos || colon == std::string::npos || colon < at) {
    FailInvalid("'" + text + "' is not AET@HOST:PORT");
  }
  Peer peer;
  peer.ae_title = text.substr(0, at);
  CheckAeTitle(peer.ae_title, "the AE title of '" + text + "'");
  peer.host = text.substr(at + 1, colon - at - 1);
  if (peer.host.size() > 2 && peer.host.front() == '[' && peer.host.back() == ']') {
    peer.host = peer.host.substr(1, peer.host.size() - 2);
  }
  if (peer.host.empty()) FailInvalid("'" + text + "' has no host");
  // DCMTK 3.6.7's network layer reads "HOST:PORT" up to the first colon: an IPv6 address was taken at
  // start and every association then failed "Illegal service parameter" (found 2026-12-07).
  if (peer.host.find(':') != std::string::npos) {
    FailInvalid("'" + text +
                "': an IPv6 address, which DCMTK's network layer cannot reach; give the PACS's "
                "IPv4 address or a host name that resolves to one");
  }
  const std::string port = text.substr(colon + 1);
  try {
    std::size_t used = 0;
    peer.port = std::stoi(port, &used);
    if (used != port.size() || port.size() > 5) peer.port = 0;  // "000000104" too (found 2026-12-07)
  } catch (const std::exception&) {
    peer.port = 0;
  }
  if (peer.port < 1 || peer.port > 65535)
    FailInvalid("'" + text + "': port '" + port + "' is not in 1..65535");
  return peer;
}

std::string PeerText(const Peer& peer) {
  return peer.ae_title + "@" + peer.host + ":" + std::to_string(peer.port);
}

}  // namespace endorecon::dicom
