// Fuzz inputs that stand for a stream of protobuf messages: each message is a 2-byte little-endian
// length and that many bytes. A message that does not parse ends the stream, as gRPC ends a call
// whose peer sends one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

namespace endorecon::fuzz {

template <typename Message>
std::vector<Message> MessagesOf(const std::uint8_t* data, std::size_t size) {
  std::vector<Message> messages;
  std::size_t at = 0;
  while (at + 2 <= size) {
    const std::size_t length = data[at] | (std::size_t{data[at + 1]} << 8);
    at += 2;
    if (at + length > size) break;
    Message message;
    if (!message.ParseFromArray(data + at, static_cast<int>(length))) break;
    messages.push_back(std::move(message));
    at += length;
  }
  return messages;
}

}  // namespace endorecon::fuzz
