#include "tests/e2e/headless_chromium.h"

#include <fcntl.h>
#include <openssl/evp.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <stdexcept>
#include <thread>

extern char** environ;

namespace endorecon::testing {
namespace {

using Clock = std::chrono::steady_clock;

// The flags this sandbox needs: no setuid sandbox (tests run as root), no GPU (WebGL falls back to
// SwiftShader), and nothing that reaches out to the network.
std::vector<std::string> Arguments(const std::filesystem::path& profile) {
  return {HeadlessChromium::kBinary,
          "--headless",
          "--no-sandbox",
          "--disable-gpu",
          "--enable-unsafe-swiftshader",
          "--disable-quic",
          "--no-first-run",
          "--disable-background-networking",
          "--disable-component-update",
          "--disable-sync",
          "--disable-dev-shm-usage",
          "--user-data-dir=" + profile.string(),
          "--remote-debugging-pipe",
          "about:blank"};
}

std::string ArgumentText(const nlohmann::json& args) {
  std::string text;
  for (const auto& arg : args) {
    if (!text.empty()) text += " ";
    text += arg.contains("value") ? arg["value"].dump() : arg.value("description", arg.value("type", ""));
  }
  return text;
}

}  // namespace

std::string DecodeBase64(const std::string& text) {
  std::string out(text.size() / 4 * 3 + 3, '\0');
  const int size = EVP_DecodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                                   reinterpret_cast<const unsigned char*>(text.data()), int(text.size()));
  if (size < 0) throw std::runtime_error("not valid base64");
  // EVP_DecodeBlock counts the padding's zero bytes too.
  std::size_t padding = 0;
  for (std::size_t i = text.size(); i > 0 && text[i - 1] == '='; --i) ++padding;
  out.resize(std::size_t(size) - padding);
  return out;
}

HeadlessChromium::HeadlessChromium(int width, int height) {
  if (access(kBinary, X_OK) != 0) {
    throw std::runtime_error(std::string(kBinary) + " is not installed (scripts/install-deps installs it)");
  }
  int to[2], from[2];
  if (pipe2(to, O_CLOEXEC) != 0 || pipe2(from, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, to[0], 3);
  posix_spawn_file_actions_adddup2(&actions, from[1], 4);
  const std::string log = (profile_.path() / "chromium.log").string();
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  const auto arguments = Arguments(profile_.path() / "profile");
  std::vector<char*> argv;
  for (const auto& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  const int spawned = posix_spawn(&pid_, kBinary, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(to[0]);
  close(from[1]);
  to_browser_ = to[1];
  from_browser_ = from[0];
  if (spawned != 0) {
    pid_ = -1;
    throw std::runtime_error(std::string("cannot start ") + kBinary);
  }
  try {
    const auto target =
        Send("Target.createTarget", {{"url", "about:blank"}}, false, std::chrono::seconds(30));
    session_ = Send("Target.attachToTarget", {{"targetId", target["targetId"]}, {"flatten", true}}, false,
                    std::chrono::seconds(30))["sessionId"];
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string(kBinary) + " did not answer over the DevTools pipe (" + e.what() +
                             "): " + ReadBytes(log).substr(0, 400));
  }
  for (const char* domain : {"Page.enable", "Runtime.enable", "Log.enable", "Network.enable"}) Call(domain);
  Call("Emulation.setDeviceMetricsOverride",
       {{"width", width}, {"height", height}, {"deviceScaleFactor", 1}, {"mobile", false}});
}

HeadlessChromium::~HeadlessChromium() {
  if (pid_ > 0) {
    try {
      Send("Browser.close", nlohmann::json::object(), false, std::chrono::seconds(5));
    } catch (const std::exception&) {
      // Killed below.
    }
    int status = 0;
    const auto deadline = Clock::now() + std::chrono::seconds(5);
    while (waitpid(pid_, &status, WNOHANG) == 0) {
      if (Clock::now() > deadline) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  if (to_browser_ >= 0) close(to_browser_);
  if (from_browser_ >= 0) close(from_browser_);
}

nlohmann::json HeadlessChromium::Send(const std::string& method, const nlohmann::json& params, bool to_page,
                                      std::chrono::seconds limit) {
  const int id = next_id_++;
  nlohmann::json message = {{"id", id}, {"method", method}, {"params", params}};
  if (to_page) message["sessionId"] = session_;
  std::string bytes = message.dump();
  bytes.push_back('\0');
  for (std::size_t sent = 0; sent < bytes.size();) {
    const ssize_t n = write(to_browser_, bytes.data() + sent, bytes.size() - sent);
    if (n <= 0) throw std::runtime_error("the browser closed its pipe");
    sent += std::size_t(n);
  }
  const auto deadline = Clock::now() + limit;
  for (;;) {
    const nlohmann::json reply = Receive(deadline);
    if (!reply.contains("id")) {
      OnEvent(reply);
      continue;
    }
    if (reply["id"] != id) continue;
    if (reply.contains("error")) throw std::runtime_error(method + ": " + reply["error"].dump());
    return reply.value("result", nlohmann::json::object());
  }
}

nlohmann::json HeadlessChromium::Receive(Clock::time_point deadline) {
  for (;;) {
    const auto end = pending_.find('\0');
    if (end != std::string::npos) {
      const std::string message = pending_.substr(0, end);
      pending_.erase(0, end + 1);
      return nlohmann::json::parse(message);
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) throw std::runtime_error("no answer in time");
    pollfd fd{from_browser_, POLLIN, 0};
    if (poll(&fd, 1, int(left)) <= 0) continue;
    char buffer[65536];
    const ssize_t n = read(from_browser_, buffer, sizeof buffer);
    if (n <= 0) throw std::runtime_error("the browser closed its pipe");
    pending_.append(buffer, std::size_t(n));
  }
}

void HeadlessChromium::OnEvent(const nlohmann::json& message) {
  const std::string method = message.value("method", "");
  const auto& params = message.contains("params") ? message["params"] : nlohmann::json::object();
  if (method == "Page.loadEventFired") {
    loaded_ = true;
  } else if (method == "Runtime.consoleAPICalled") {
    const std::string type = params.value("type", "");
    if (type == "error" || type == "assert")
      problems_.push_back("console." + type + ": " + ArgumentText(params["args"]));
  } else if (method == "Runtime.exceptionThrown") {
    const auto& details = params["exceptionDetails"];
    problems_.push_back("uncaught: " +
                        (details.contains("exception")
                             ? details["exception"].value("description", details.value("text", ""))
                             : details.value("text", "")));
  } else if (method == "Log.entryAdded") {
    const auto& entry = params["entry"];
    if (entry.value("level", "") == "error")
      problems_.push_back("log: " + entry.value("text", "") + " " + entry.value("url", ""));
  } else if (method == "Network.loadingFailed") {
    problems_.push_back("failed load: " + params.value("errorText", "") + " (" + params.value("type", "") +
                        ")");
  } else if (method == "Network.requestWillBeSent") {
    const std::string url = params["request"].value("url", "");
    const bool local = url.rfind("file:", 0) == 0 || url.rfind("data:", 0) == 0 ||
                       url.rfind("blob:", 0) == 0 || url.rfind("about:", 0) == 0;
    if (!local) problems_.push_back("network request: " + url.substr(0, 200));
  }
}

nlohmann::json HeadlessChromium::Call(const std::string& method, const nlohmann::json& params,
                                      std::chrono::seconds limit) {
  return Send(method, params, true, limit);
}

void HeadlessChromium::Navigate(const std::string& url) {
  loaded_ = false;
  const auto result = Call("Page.navigate", {{"url", url}});
  if (result.contains("errorText"))
    throw std::runtime_error("cannot open " + url + ": " + result["errorText"].dump());
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (!loaded_) OnEvent(Receive(deadline));
}

nlohmann::json HeadlessChromium::Evaluate(const std::string& expression) {
  const auto result =
      Call("Runtime.evaluate", {{"expression", expression}, {"returnByValue", true}, {"awaitPromise", true}});
  if (result.contains("exceptionDetails")) {
    const auto& details = result["exceptionDetails"];
    throw std::runtime_error("page script failed: " + (details.contains("exception")
                                                           ? details["exception"].value("description", "")
                                                           : details.value("text", "")));
  }
  return result["result"].value("value", nlohmann::json());
}

bool HeadlessChromium::WaitFor(const std::string& expression, std::chrono::milliseconds limit) {
  const auto deadline = Clock::now() + limit;
  for (;;) {
    if (Evaluate(expression) == true) return true;
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
}

std::string HeadlessChromium::Screenshot(double x, double y, double width, double height) {
  nlohmann::json params = {{"format", "png"}};
  if (width > 0) {
    params["clip"] = {{"x", x}, {"y", y}, {"width", width}, {"height", height}, {"scale", 1}};
  } else {
    const auto metrics = Call("Page.getLayoutMetrics");
    const auto& size = metrics["cssContentSize"];
    params["captureBeyondViewport"] = true;
    params["clip"] = {{"x", 0}, {"y", 0}, {"width", size["width"]}, {"height", size["height"]}, {"scale", 1}};
  }
  return DecodeBase64(Call("Page.captureScreenshot", params, std::chrono::seconds(60))["data"]);
}

void HeadlessChromium::Drag(double x0, double y0, double x1, double y1, int steps) {
  const auto mouse = [&](const char* type, double x, double y, int buttons) {
    Call("Input.dispatchMouseEvent",
         {{"type", type}, {"x", x}, {"y", y}, {"button", "left"}, {"buttons", buttons}, {"clickCount", 1}});
  };
  mouse("mousePressed", x0, y0, 1);
  for (int i = 1; i <= steps; ++i) {
    mouse("mouseMoved", x0 + (x1 - x0) * i / steps, y0 + (y1 - y0) * i / steps, 1);
  }
  mouse("mouseReleased", x1, y1, 0);
}

void HeadlessChromium::PressKey(const std::string& key, int code) {
  for (const char* type : {"rawKeyDown", "keyUp"}) {
    Call("Input.dispatchKeyEvent",
         {{"type", type}, {"key", key}, {"code", key}, {"windowsVirtualKeyCode", code}});
  }
}

}  // namespace endorecon::testing
