// A real browser for tests: Debian's headless Chromium driven over the DevTools protocol on a pipe
// (--remote-debugging-pipe: JSON messages ended by NUL on file descriptors 3 and 4), so no WebSocket
// client or npm package is needed. One browser, one page, a fresh profile; nothing on the network.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/unit/temp_dir.h"

namespace endorecon::testing {

class HeadlessChromium {
 public:
  static constexpr const char* kBinary = "/usr/bin/chromium";

  // Starts Chromium and opens a page of width x height CSS pixels. Throws std::runtime_error saying
  // why when it cannot (not installed, exits at once, no answer within 30 s): the caller skips.
  HeadlessChromium(int width, int height);
  ~HeadlessChromium();
  HeadlessChromium(const HeadlessChromium&) = delete;
  HeadlessChromium& operator=(const HeadlessChromium&) = delete;

  // A protocol command on the page; returns its result. Throws std::runtime_error on a protocol
  // error or no answer within `limit`.
  nlohmann::json Call(const std::string& method, const nlohmann::json& params = nlohmann::json::object(),
                      std::chrono::seconds limit = std::chrono::seconds(30));
  // Opens `url` and waits for its load event.
  void Navigate(const std::string& url);
  // The value of a JavaScript expression in the page (a promise is awaited); throws with the
  // exception's text when it throws.
  nlohmann::json Evaluate(const std::string& expression);
  // Polls `expression` until it is true; false after `limit`.
  bool WaitFor(const std::string& expression, std::chrono::milliseconds limit);
  // A PNG of the page's region (CSS pixels; the whole page when width is 0).
  std::string Screenshot(double x = 0, double y = 0, double width = 0, double height = 0);
  // A drag with the left mouse button from (x0, y0) to (x1, y1) in `steps` moves.
  void Drag(double x0, double y0, double x1, double y1, int steps);
  // A key press (DOM key name and Windows key code, e.g. "ArrowRight", 39) to the focused element.
  void PressKey(const std::string& key, int code);

  // What went wrong in the page so far: console errors, uncaught exceptions, error log entries,
  // failed loads, and any request that is not to a file:, data:, blob: or about: URL.
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  nlohmann::json Send(const std::string& method, const nlohmann::json& params, bool to_page,
                      std::chrono::seconds limit);
  nlohmann::json Receive(std::chrono::steady_clock::time_point deadline);
  void OnEvent(const nlohmann::json& message);

  TempDir profile_{"chromium-profile"};
  pid_t pid_ = -1;
  int to_browser_ = -1, from_browser_ = -1;
  std::string pending_;
  int next_id_ = 1;
  std::string session_;
  bool loaded_ = false;
  std::vector<std::string> problems_;
};

// Decodes standard base64 (the protocol's screenshots and the page's data: URIs).
std::string DecodeBase64(const std::string& text);

}  // namespace endorecon::testing
