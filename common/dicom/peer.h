// A DICOM application entity on the network: a PACS, or the server's own storage SCP.
#pragma once

#include <string>

namespace endorecon::dicom {

struct Peer {
  std::string ae_title;
  std::string host;
  int port = 0;
};

// "AET@HOST:PORT" (HOST may be [IPv6]). Throws InvalidArgument naming `text` unless the AE title
// is 1 to 16 characters of printable ASCII without backslash and the port is in 1..65535.
Peer ParsePeer(const std::string& text);
// Throws InvalidArgument naming `what` unless `ae_title` is a valid AE title.
void CheckAeTitle(const std::string& ae_title, const std::string& what);
// "AET@HOST:PORT".
std::string PeerText(const Peer& peer);

}  // namespace endorecon::dicom
