// A minimal W3C WebDriver client for browser tests: starts Debian's
// chromedriver as a child process on a free port and drives headless
// Chromium through it with httplib. Header-only so that any test file can
// include it without changing the test build.
#pragma once

#include <fcntl.h>
#include <httplib.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/config.h"

namespace doasido::testing {

inline const char* kChromium = "/usr/bin/chromium";
inline const char* kChromeDriver = "/usr/bin/chromedriver";

inline bool ChromiumAvailable() {
  return access(kChromium, X_OK) == 0 && access(kChromeDriver, X_OK) == 0;
}

// A loopback TCP port that was free a moment ago.
inline int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    if (fd >= 0) close(fd);
    throw std::runtime_error("no free port");
  }
  close(fd);
  return ntohs(addr.sin_port);
}

inline std::string Base64Decode(const std::string& in) {
  std::string out;
  unsigned buffer = 0;
  int bits = 0;
  for (char c : in) {
    int v;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    else if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    else if (c >= '0' && c <= '9') v = c - '0' + 52;
    else if (c == '+') v = 62;
    else if (c == '/') v = 63;
    else continue;  // padding and line breaks
    buffer = (buffer << 6) | static_cast<unsigned>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((buffer >> bits) & 0xff);
    }
  }
  return out;
}

// WebDriver key codes for keys that are not characters.
namespace keys {
inline const std::string kArrowLeft = "\xEE\x80\x92";   // U+E012
inline const std::string kArrowUp = "\xEE\x80\x93";     // U+E013
inline const std::string kArrowRight = "\xEE\x80\x94";  // U+E014
inline const std::string kArrowDown = "\xEE\x80\x95";   // U+E015
}  // namespace keys

// A chromedriver child process, killed (by its pid) on destruction.
class ChromeDriver {
 public:
  explicit ChromeDriver(const std::filesystem::path& log = "/dev/null") : port_(FreePort()) {
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
      }
      const std::string port_arg = "--port=" + std::to_string(port_);
      execl(kChromeDriver, kChromeDriver, port_arg.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    if (pid_ < 0) throw std::runtime_error("fork failed");
    httplib::Client client("127.0.0.1", port_);
    for (int i = 0; i < 200; ++i) {
      if (auto r = client.Get("/status"); r && r->status == 200) {
        if (Json::parse(r->body)["value"].value("ready", false)) return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    Kill();
    throw std::runtime_error("chromedriver did not become ready");
  }
  ~ChromeDriver() { Kill(); }
  ChromeDriver(const ChromeDriver&) = delete;
  ChromeDriver& operator=(const ChromeDriver&) = delete;
  int port() const { return port_; }

 private:
  void Kill() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      waitpid(pid_, nullptr, 0);
      pid_ = -1;
    }
  }
  int port_;
  pid_t pid_ = -1;
};

// One browser session (one headless Chromium). Every call throws
// std::runtime_error with the driver's message when the driver reports an
// error.
class WebDriverSession {
 public:
  // `extra_args` are added to Chromium's command line (e.g. software WebGL).
  explicit WebDriverSession(const ChromeDriver& driver, int width = 1400, int height = 900,
                            const std::vector<std::string>& extra_args = {})
      : client_("127.0.0.1", driver.port()) {
    client_.set_read_timeout(120, 0);
    client_.set_connection_timeout(10, 0);
    Json caps = {
        {"capabilities",
         {{"alwaysMatch",
           {{"browserName", "chrome"},
            {"goog:chromeOptions",
             {{"binary", kChromium},
              {"args",
               {"--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--autoplay-policy=no-user-gesture-required", "--mute-audio",
                "--window-size=" + std::to_string(width) + "," + std::to_string(height)}}}}}}}}};
    for (const auto& a : extra_args) {
      caps["capabilities"]["alwaysMatch"]["goog:chromeOptions"]["args"].push_back(a);
    }
    const Json value = Call("POST", "/session", caps);
    id_ = value.at("sessionId").get<std::string>();
  }
  ~WebDriverSession() {
    if (!id_.empty()) client_.Delete("/session/" + id_);
  }
  WebDriverSession(const WebDriverSession&) = delete;
  WebDriverSession& operator=(const WebDriverSession&) = delete;

  void Navigate(const std::string& url) { Call("POST", Path("/url"), {{"url", url}}); }

  // Runs `script` as a function body (arguments in `arguments`), returning
  // its JSON-serialisable result.
  Json Execute(const std::string& script, const Json& args = Json::array()) {
    return Call("POST", Path("/execute/sync"), {{"script", script}, {"args", args}});
  }
  // As Execute, but the script calls arguments[arguments.length - 1](v).
  Json ExecuteAsync(const std::string& script, const Json& args = Json::array()) {
    return Call("POST", Path("/execute/async"), {{"script", script}, {"args", args}});
  }
  // Polls `expression` (a JS expression) until it is truthy; returns its
  // value, or throws with `what` after `timeout_s`.
  Json WaitFor(const std::string& expression, const std::string& what, double timeout_s = 15) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    Json v;
    while (std::chrono::steady_clock::now() < end) {
      v = Execute("return (" + expression + ");");
      if (!v.is_null() && v != false && v != 0 && v != "") return v;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    throw std::runtime_error("timed out waiting for " + what + " (" + expression +
                             " = " + v.dump() + ")");
  }

  // Types `keys` on the focused element with real key events (Actions API):
  // each entry is one key, pressed and released.
  void PressKeys(const std::vector<std::string>& keys) {
    Json actions = Json::array();
    for (const auto& k : keys) {
      actions.push_back({{"type", "keyDown"}, {"value", k}});
      actions.push_back({{"type", "keyUp"}, {"value", k}});
    }
    Call("POST", Path("/actions"),
         {{"actions", {{{"type", "key"}, {"id", "keyboard"}, {"actions", actions}}}}});
    Call("DELETE", Path("/actions"), nullptr);
  }

  // The element's rectangle {x, y, width, height} in CSS pixels.
  Json Rect(const std::string& css) {
    const Json e = Call("POST", Path("/element"), {{"using", "css selector"}, {"value", css}});
    const std::string id = e.begin().value().get<std::string>();
    return Call("GET", Path("/element/" + id + "/rect"), nullptr);
  }

  // Writes a PNG of the viewport.
  void Screenshot(const std::filesystem::path& png) {
    const std::string data = Call("GET", Path("/screenshot"), nullptr).get<std::string>();
    std::filesystem::create_directories(png.parent_path());
    std::ofstream(png, std::ios::binary) << Base64Decode(data);
  }

 private:
  std::string Path(const std::string& tail) const { return "/session/" + id_ + tail; }

  Json Call(const std::string& method, const std::string& path, const Json& body) {
    httplib::Result r = method == "GET"      ? client_.Get(path)
                        : method == "DELETE" ? client_.Delete(path)
                                             : client_.Post(path, body.dump(), "application/json");
    if (!r) throw std::runtime_error("WebDriver " + path + ": " + httplib::to_string(r.error()));
    const Json reply = Json::parse(r->body, nullptr, false);
    if (r->status != 200 || reply.is_discarded()) {
      throw std::runtime_error("WebDriver " + path + ": HTTP " + std::to_string(r->status) +
                               " " + r->body.substr(0, 600));
    }
    return reply.value("value", Json());
  }

  httplib::Client client_;
  std::string id_;
};

// Helpers for pages with a WebGL canvas #view (the /verify page).
// Keeps the view's pixels in window[var] for ChangedPixels.
inline void SnapshotView(WebDriverSession& session, const std::string& var) {
  session.Execute(R"js(
    const v = document.getElementById('view');
    const c = document.createElement('canvas'); c.width = v.width; c.height = v.height;
    const g = c.getContext('2d'); g.drawImage(v, 0, 0);
    window[arguments[0]] = g.getImageData(0, 0, c.width, c.height).data;
  )js", Json::array({var}));
}

inline int ChangedPixels(WebDriverSession& session, const std::string& before_var) {
  return session.Execute(R"js(
    const v = document.getElementById('view');
    const c = document.createElement('canvas'); c.width = v.width; c.height = v.height;
    const g = c.getContext('2d'); g.drawImage(v, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data, b = window[arguments[0]];
    let n = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i] !== b[i] || d[i + 1] !== b[i + 1] || d[i + 2] !== b[i + 2]) ++n;
    return n;
  )js", Json::array({before_var})).get<int>();
}

// Chromium flags for WebGL through SwiftShader.
inline const std::vector<std::string> kWebGlFlags = {"--enable-unsafe-swiftshader", "--use-angle=swiftshader",
                                              "--ignore-gpu-blocklist"};

}  // namespace doasido::testing
