// Streams of protobuf messages from memory: fuzz inputs that stand for one (each message a 2-byte
// little-endian length and that many bytes; a message that does not parse ends the stream, as gRPC
// ends a call whose peer sends one), and the gRPC reader interfaces that hand such a list out, for
// the stream handlers under test (the fuzz harnesses, and tests that feed a handler by hand).
#pragma once

#include <grpcpp/support/sync_stream.h>

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <utility>
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

// Hands out `messages` one after another, then ends, as `Reader` (a gRPC reader interface) does.
template <typename Message, typename Reader>
class ReaderOf : public Reader {
 public:
  explicit ReaderOf(std::vector<Message> messages) : messages_(std::move(messages)) {}
  bool NextMessageSize(std::uint32_t* size) override {
    if (next_ >= messages_.size()) return false;
    *size = static_cast<std::uint32_t>(messages_[next_].ByteSizeLong());
    return true;
  }
  bool Read(Message* message) override {
    if (next_ >= messages_.size()) return false;
    *message = messages_[next_++];
    return true;
  }

 private:
  std::vector<Message> messages_;
  std::size_t next_ = 0;
};

// What a client reads from a server stream (a download), ending with OK.
template <typename Message>
class ClientStreamOf final : public ReaderOf<Message, grpc::ClientReaderInterface<Message>> {
 public:
  using ReaderOf<Message, grpc::ClientReaderInterface<Message>>::ReaderOf;
  void WaitForInitialMetadata() override {}
  grpc::Status Finish() override { return grpc::Status::OK; }
};

// What a server handler reads from a client stream (an upload).
template <typename Message>
class ServerStreamOf final : public ReaderOf<Message, grpc::ServerReaderInterface<Message>> {
 public:
  using ReaderOf<Message, grpc::ServerReaderInterface<Message>>::ReaderOf;
  void SendInitialMetadata() override {}
};

}  // namespace endorecon::fuzz
