// Every occurrence of a text in another replaced, left to right, the replacement never searched
// again: how a machine's paths in a message are said as its reader knows them (a worker's scratch
// folder, the server's folder of links, a raw recording's staged names).
#pragma once

#include <string>
#include <string_view>

namespace endorecon {

std::string ReplaceAll(std::string text, std::string_view from, std::string_view to);

}  // namespace endorecon
