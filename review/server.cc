#include "review/server.h"

#include <arpa/inet.h>
#include <httplib.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <fstream>
#include <mutex>
#include <random>
#include <thread>

#include "core/error.h"
#include "core/log.h"
#include "db/database.h"
#include "filters/kept_shot.h"
#include "filters/shot_boundary.h"
#include "review/http_range.h"
#include "review/request_body.h"
#include "review/pages.h"
#include "review/study.h"
#include "review/verify_routes.h"

namespace doasido::review {
namespace {

std::string RandomHex(int bytes) {
  std::random_device rd;  // the kernel's CSPRNG on Linux
  static const char* kHex = "0123456789abcdef";
  std::string out;
  for (int i = 0; i < bytes; ++i) {
    const unsigned v = rd() & 0xffu;
    out += kHex[v >> 4];
    out += kHex[v & 15];
  }
  return out;
}

bool ConstantTimeEquals(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

void SendJson(httplib::Response& res, int status, const Json& body) {
  res.status = status;
  res.set_content(body.dump(), "application/json");
}

void SendError(httplib::Response& res, int status, const std::string& message) {
  SendJson(res, status, {{"error", message}});
}

std::string VideoType(const std::filesystem::path& path) {
  const std::string ext = Lower(path.extension().string());
  if (ext == ".mp4" || ext == ".m4v") return "video/mp4";
  if (ext == ".webm") return "video/webm";
  if (ext == ".mkv") return "video/x-matroska";
  if (ext == ".mov") return "video/quicktime";
  if (ext == ".avi") return "video/x-msvideo";
  if (ext == ".ogv") return "video/ogg";
  return "application/octet-stream";
}

// A raw request target that tries to leave its route: dot segments, their
// percent-encoded forms, encoded separators and backslashes.
bool LooksLikeTraversal(const std::string& target) {
  const std::string t = Lower(target);
  for (const char* bad : {"..", "%2e%2e", "%2e.", ".%2e", "%2f", "%5c", "\\", "%00", "//"}) {
    if (t.find(bad) != std::string::npos) return true;
  }
  return false;
}

bool ValidName(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' ||
           c == ' ' || c == '@';
  });
}

// The shot the filters judged for `clip`: the block a verdict stage copied
// into its measurements `m` (the span it judged), else the shot-boundary
// stage's own decision.
filters::KeptShot KeptShotOf(Database& db, ClipId clip, const std::optional<Json>& m) {
  if (auto judged = filters::ReadJudgedShot(m)) return *judged;
  return filters::ReadKeptShot(db.GetMeasurements(clip, filters::kShotBoundaryStageName))
      .value_or(filters::KeptShot{});
}

// What the review page shows of clip `id` for `stage`: video facts, span,
// verdict, boxes, the stage's summary, the shot the filters judged and the
// verdict history.
// Video size and rate, and the clip's span in seconds and frames.
void AddVideoAndSpan(const ClipRecord& clip, const VideoRecord& video, Json& out) {
  const double fps = video.info ? video.info->fps : 0.0;
  out["fps"] = fps;
  out["width"] = video.info ? video.info->width : 0;
  out["height"] = video.info ? video.info->height : 0;
  out["frame_count"] = video.info ? video.info->frame_count : 0;
  double start_s = 0;
  if (clip.start_s) {
    start_s = *clip.start_s;
  } else if (clip.start_frame && fps > 0) {
    start_s = static_cast<double>(*clip.start_frame) / fps;
  }
  out["start_s"] = start_s;
  out["end_s"] = nullptr;
  if (clip.end_s) {
    out["end_s"] = *clip.end_s;
  } else if (clip.end_frame && fps > 0) {
    out["end_s"] = static_cast<double>(*clip.end_frame + 1) / fps;
  }
  out["start_frame"] = clip.start_frame ? Json(*clip.start_frame) : Json(nullptr);
  out["end_frame"] = clip.end_frame ? Json(*clip.end_frame) : Json(nullptr);
}

Json DetectionsJson(const std::vector<Detection>& detections) {
  Json out = Json::array();
  for (const auto& det : detections) {
    out.push_back({{"frame", det.frame}, {"kind", det.kind}, {"x1", det.x1}, {"y1", det.y1},
                   {"x2", det.x2}, {"y2", det.y2}, {"score", det.score},
                   {"contact_state", det.contact_state}, {"hand_side", det.hand_side},
                   {"dx", det.dx}, {"dy", det.dy}, {"magnitude", det.magnitude}});
  }
  return out;
}

Json ClipJson(Database& d, ClipId id, const std::string& stage) {
  const ClipRecord clip = d.GetClip(id);
  Json out = {{"clip_id", id}, {"external_id", clip.external_id}, {"stage", stage},
              {"video_url", "/video/" + std::to_string(id)}, {"metadata", clip.metadata}};
  AddVideoAndSpan(clip, d.GetVideo(clip.video_id), out);
  std::string reason, verdict;
  for (const auto& run : d.ListRuns({.stage = stage, .clip = id})) {
    reason = run.reason;
    verdict = run.verdict;
  }
  out["reason"] = reason;
  out["verdict"] = verdict;
  out["detections"] = DetectionsJson(d.GetDetections(id));
  // The stage's own summary, and cut positions / trim from the shot
  // stage (copied into later stages' "shot" block, or its summary).
  const auto m = stage.empty() ? std::nullopt : d.GetMeasurements(id, stage);
  out["summary"] = m && m->contains("summary") ? m->at("summary") : Json(nullptr);
  const filters::KeptShot shot = KeptShotOf(d, id, m);
  out["cuts"] = shot.boundaries;
  out["trim"] = nullptr;
  if (shot.trim) {
    out["trim"] = {{"start_frame", shot.trim->start_frame},
                   {"end_frame", shot.trim->end_frame}};
  }
  Json history = Json::array();
  for (const auto& v : d.VerdictHistory(id, stage)) {
    history.push_back({{"verdict", v.verdict}, {"reason", v.reason}, {"source", v.source},
                       {"at", v.created_at}});
  }
  out["history"] = history;
  // Every stage the clip went through: flags do not stop the filters, so a
  // person sees what each of them made of the clip.
  Json stages = Json::array();
  for (const auto& run : d.ListRuns({.clip = id})) {
    if (run.state != RunState::kDone) continue;
    const auto rm = d.GetMeasurements(id, run.stage);
    const Json scores = rm && rm->contains("summary") && rm->at("summary").contains("scores")
                            ? rm->at("summary").at("scores")
                            : Json::array();
    stages.push_back({{"stage", run.stage}, {"verdict", run.verdict}, {"reason", run.reason},
                      {"scores", scores}});
  }
  out["stages"] = stages;
  return out;
}

}  // namespace

bool IsLoopbackHost(const std::string& host_in) {
  std::string host = host_in;
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  if (Lower(host) == "localhost") return true;
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) {
    if (IN6_IS_ADDR_LOOPBACK(&v6)) return true;
    if (IN6_IS_ADDR_V4MAPPED(&v6)) return v6.s6_addr[12] == 127;
  }
  return false;
}

struct ReviewServer::Impl {
  ServeOptions options;
  std::unique_ptr<Database> db;
  std::mutex db_mutex;  // Database belongs to one thread; handlers run on a pool
  httplib::Server http;
  std::thread thread;
  std::string token = RandomHex(32);
  int port = 0;
  std::vector<std::string> origins;  // allowed Origin values
  std::vector<std::string> hosts;    // allowed Host values (loopback binds)

  std::string UrlHost() const {
    return options.host.find(':') != std::string::npos && options.host.front() != '['
               ? "[" + options.host + "]"
               : options.host;
  }

  void Bind() {
    port = options.port == 0 ? http.bind_to_any_port(options.host)
                             : (http.bind_to_port(options.host, options.port) ? options.port : -1);
    if (port <= 0) {
      throw Error("bind", "cannot listen on " + options.host + ":" +
                              std::to_string(options.port) + " (in use, or not an address of "
                                                             "this machine)",
                  {.field = "host/port"});
    }
    const std::string p = std::to_string(port);
    std::vector<std::string> names = {UrlHost()};
    if (IsLoopbackHost(options.host)) {
      for (const char* n : {"127.0.0.1", "localhost", "[::1]"}) names.push_back(n);
    }
    for (const auto& n : names) {
      hosts.push_back(n + ":" + p);
      origins.push_back("http://" + n + ":" + p);
    }
  }

  bool SameOrigin(const httplib::Request& req) const {
    const std::string origin = req.get_header_value("Origin");
    if (!origin.empty()) {
      return std::find(origins.begin(), origins.end(), origin) != origins.end();
    }
    const std::string referer = req.get_header_value("Referer");
    for (const auto& o : origins) {
      if (referer.compare(0, o.size() + 1, o + "/") == 0) return true;
    }
    return false;
  }

  // Runs fn with the database under the lock, turning doasido errors into
  // JSON error responses.
  template <typename Fn>
  void WithDb(httplib::Response& res, Fn fn) {
    std::lock_guard<std::mutex> lock(db_mutex);
    try {
      fn(*db);
    } catch (const Error& e) {
      const int status = e.code() == "not_flagged" || e.code() == "trial_exists" ? 409
                         : e.code().rfind("no_such", 0) == 0                  ? 404
                                                                              : 400;
      SendError(res, status, e.what());
    } catch (const Json::exception& e) {
      SendError(res, 400, std::string("bad JSON: ") + e.what());
    } catch (const std::logic_error& e) {  // ids out of range in the URL
      SendError(res, 400, std::string("bad request: ") + e.what());
    }
  }

  void ServeFile(const httplib::Request& req, httplib::Response& res,
                 const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
      return SendError(res, 404, "the video file of this item is missing");
    }
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    const RangeDecision range = DecideRange(req.get_header_value("Range"), size);
    // httplib slices bodies by the request's Range itself, without checking
    // the end against the size; the route answers ranges on its own.
    const_cast<httplib::Request&>(req).ranges.clear();
    res.set_header("Accept-Ranges", "bytes");
    res.set_header("Cache-Control", "no-cache");
    if (range.kind == RangeKind::kUnsatisfiable) {
      res.status = 416;
      res.set_header("Content-Range", ContentRange(range, size));
      return;
    }
    const std::uint64_t first = range.kind == RangeKind::kPartial ? range.first : 0;
    const std::uint64_t length = size == 0 ? 0 : range.last - first + 1;
    if (range.kind == RangeKind::kPartial) {
      res.status = 206;
      res.set_header("Content-Range", ContentRange(range, size));
    } else {
      res.status = 200;
    }
    auto file = std::make_shared<std::ifstream>(path, std::ios::binary);
    res.set_content_provider(
        static_cast<size_t>(length), VideoType(path),
        [file, first](size_t offset, size_t want, httplib::DataSink& sink) {
          std::vector<char> buffer(std::min<size_t>(want, 1 << 16));
          file->clear();
          file->seekg(static_cast<std::streamoff>(first + offset));
          file->read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
          const auto got = file->gcount();
          if (got <= 0) return false;
          return sink.write(buffer.data(), static_cast<size_t>(got));
        });
  }

  void SendPage(httplib::Response& res, const std::string& nonce, const std::string& html) {
    res.set_header("Content-Security-Policy",
                   "default-src 'none'; script-src 'nonce-" + nonce + "'; style-src 'nonce-" +
                       nonce + "'; img-src 'self' data:; media-src 'self'; connect-src 'self'; "
                       "base-uri 'none'; form-action 'self'; frame-ancestors 'none'");
    res.set_content(html, "text/html; charset=utf-8");
  }

  void Routes();
  void GuardRoutes();
  void ReviewRoutes();
  void StudyPages();
  void StudyApi();

  // A person's decision on a flagged run (POST /api/decision).
  void Decide(Database& d, const Json& body, httplib::Response& res) {
    DecisionRequest r = ReadDecision(body);
    if (r.reason.empty()) r.reason = "accepted on review";
    d.RecordReview(r.clip, r.stage, r.reviewer, r.accept, r.reason);
    SendJson(res, 200, {{"ok", true}, {"remaining", d.CountFlagged()}});
  }
};

void ReviewServer::Impl::Routes() {
  // Responses go out as header and body writes; without TCP_NODELAY the
  // second waits on the client's delayed ACK (~40 ms per small response).
  http.set_tcp_nodelay(true);
  http.set_keep_alive_timeout(2);
  http.set_payload_max_length(1 << 20);
  GuardRoutes();
  ReviewRoutes();
  StudyPages();
  StudyApi();
}

// Every request: no path traversal, the expected Host on loopback binds
// (against DNS rebinding), the token and same origin for writes; every
// response: no sniffing, framing or caching.
void ReviewServer::Impl::GuardRoutes() {
  http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (LooksLikeTraversal(req.target)) {
      SendError(res, 400, "path traversal is not allowed");
      return httplib::Server::HandlerResponse::Handled;
    }
    if (IsLoopbackHost(options.host)) {
      const std::string host = Lower(req.get_header_value("Host"));
      if (std::find(hosts.begin(), hosts.end(), host) == hosts.end()) {
        SendError(res, 403, "unexpected Host header (DNS rebinding?)");
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    if (req.method != "GET" && req.method != "HEAD") {
      if (!ConstantTimeEquals(req.get_header_value("X-Doasido-Token"), token)) {
        SendError(res, 403, "missing or wrong X-Doasido-Token: reload the page");
        return httplib::Server::HandlerResponse::Handled;
      }
      if (!SameOrigin(req)) {
        SendError(res, 403, "cross-origin request refused");
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });

  http.set_post_routing_handler([](const httplib::Request&, httplib::Response& res) {
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_header("X-Frame-Options", "DENY");
    res.set_header("Referrer-Policy", "same-origin");
    res.set_header("Cross-Origin-Resource-Policy", "same-origin");
    if (!res.has_header("Content-Security-Policy")) {
      res.set_header("Content-Security-Policy", "default-src 'none'; frame-ancestors 'none'");
    }
    if (!res.has_header("Cache-Control")) res.set_header("Cache-Control", "no-store");
  });
}

// The flagged-clip review: page, queue, clip facts, video and decisions.
void ReviewServer::Impl::ReviewRoutes() {
  http.Get("/", [this](const httplib::Request&, httplib::Response& res) {
    const std::string nonce = RandomHex(16);
    const Json config = {{"token", token},
                         {"reviewer", options.reviewer},
                         {"reason_for_stage", options.default_reasons}};
    SendPage(res, nonce, ReviewPage(nonce, config, options.stage_reasons));
  });

  http.Get("/api/queue", [this](const httplib::Request&, httplib::Response& res) {
    WithDb(res, [&](Database& d) {
      Json items = Json::array();
      for (const auto& f : d.ListFlagged()) {
        items.push_back({{"clip_id", f.clip_id},
                         {"external_id", f.external_id},
                         {"stage", f.stage},
                         {"reason", f.reason}});
      }
      SendJson(res, 200, {{"items", items}});
    });
  });

  http.Get(R"(/api/clip/(\d+))", [this](const httplib::Request& req, httplib::Response& res) {
    WithDb(res, [&](Database& d) {
      SendJson(res, 200, ClipJson(d, PathId(req.matches[1].str()), req.get_param_value("stage")));
    });
  });

  http.Get(R"(/video/(\d+))", [this](const httplib::Request& req, httplib::Response& res) {
    std::filesystem::path path;
    WithDb(res, [&](Database& d) {
      path = d.GetVideo(d.GetClip(PathId(req.matches[1].str())).video_id).path;
    });
    if (path.empty()) return;  // WithDb answered with the error
    if (path.string().find("://") != std::string::npos) {
      return SendError(res, 404, "this clip's video is a URL, not a local file");
    }
    ServeFile(req, res, path);
  });

  http.Post("/api/decision", [this](const httplib::Request& req, httplib::Response& res) {
    WithDb(res, [&](Database& d) { Decide(d, ParseRequestBody(req.body), res); });
  });
}

// Preference studies: the rating page and the summary page.
void ReviewServer::Impl::StudyPages() {
  http.Get(R"(/study/([A-Za-z0-9_.\-]+))", [this](const httplib::Request& req,
                                                  httplib::Response& res) {
    const std::string name = req.matches[1].str();
    const std::string rater = req.get_param_value("rater");
    if (!rater.empty() && !ValidName(rater)) {
      return SendError(res, 400, "a rater name uses letters, digits, ' ', '_', '-', '.', '@'");
    }
    bool found = false;
    WithDb(res, [&](Database& d) { found = d.GetStudy(name).has_value(); });
    if (!found) return SendError(res, 404, "no study named '" + name + "'");
    const std::string nonce = RandomHex(16);
    SendPage(res, nonce,
             StudyPage(nonce, {{"token", token}, {"study", name}, {"rater", rater}}));
  });

  http.Get(R"(/study/([A-Za-z0-9_.\-]+)/summary)", [this](const httplib::Request& req,
                                                          httplib::Response& res) {
    WithDb(res, [&](Database& d) {
      const StudySummary s = SummarizeStudy(d, req.matches[1].str());
      const std::string nonce = RandomHex(16);
      SendPage(res, nonce, StudySummaryPage(nonce, s));
    });
  });

}

// Preference studies: summary, the next trial of a rater, answers and the
// trial's videos (sides resolved here).
void ReviewServer::Impl::StudyApi() {
  http.Get(R"(/api/study/([A-Za-z0-9_.\-]+)/summary)",
           [this](const httplib::Request& req, httplib::Response& res) {
             WithDb(res, [&](Database& d) {
               SendJson(res, 200, ToJson(SummarizeStudy(d, req.matches[1].str())));
             });
           });

  http.Get(R"(/api/study/([A-Za-z0-9_.\-]+)/next)", [this](const httplib::Request& req,
                                                         httplib::Response& res) {
    const std::string rater = req.get_param_value("rater");
    if (!ValidName(rater)) return SendError(res, 400, "a valid rater name is required");
    WithDb(res, [&](Database& d) {
      const auto study = d.GetStudy(req.matches[1].str());
      if (!study) return SendError(res, 404, "no such study");
      int rated = 0;
      for (const auto& t : d.GetStudyTrials(study->id)) {
        if (t.rater == rater && !t.choice.empty()) ++rated;
      }
      const auto trial = NextTrial(d, *study, rater);
      if (!trial) return SendJson(res, 200, {{"done", true}, {"rated", rated}});
      std::string item_id;
      for (const auto& item : d.GetStudyItems(study->id)) {
        if (item.id == trial->item) item_id = item.item_id;
      }
      const std::string media = "/media/trial/" + std::to_string(trial->id) + "/";
      SendJson(res, 200, {{"done", false}, {"trial_id", trial->id}, {"item_id", item_id},
                          {"source_url", media + "source"}, {"left_url", media + "left"},
                          {"right_url", media + "right"}, {"rated", rated}});
    });
  });

  http.Post(R"(/api/study/([A-Za-z0-9_.\-]+)/answer)", [this](const httplib::Request& req,
                                                            httplib::Response& res) {
    WithDb(res, [&](Database& d) {
      const Json body = ParseRequestBody(req.body);
      const std::int64_t trial_id = RequireId(body, "trial_id");
      const std::string rater = body.at("rater").get<std::string>();
      const std::string side = body.at("choice").get<std::string>();
      const auto study = d.GetStudy(req.matches[1].str());
      const auto trial = d.GetStudyTrial(trial_id);
      bool in_study = false;
      if (study && trial) {
        for (const auto& item : d.GetStudyItems(study->id)) in_study |= item.id == trial->item;
      }
      if (!in_study) return SendError(res, 404, "no such trial in this study");
      if (!d.AnswerStudyTrial(trial_id, rater, side)) {
        return SendError(res, 409,
                         "this trial is answered already, is another rater's, or its item has "
                         "all its ratings");
      }
      SendJson(res, 200, {{"ok", true}});
    });
  });

  http.Get(R"(/media/trial/(\d+)/(source|left|right))", [this](const httplib::Request& req,
                                                             httplib::Response& res) {
    std::filesystem::path path;
    WithDb(res, [&](Database& d) {
      const auto trial = d.GetStudyTrial(PathId(req.matches[1].str()));
      const auto item = trial ? d.GetStudyItem(trial->item) : std::nullopt;
      if (!item) return SendError(res, 404, "no such trial");
      // Left and right are resolved here so that the page never learns
      // from a URL which side shows which method.
      const std::string role = req.matches[2].str();
      if (role == "source") {
        path = item->source_video;
      } else {
        path = (role == "left") == trial->left_is_a ? item->a_video : item->b_video;
      }
    });
    if (!path.empty()) ServeFile(req, res, path);
  });

  AddVerifyRoutes(http, {.with_db = [this](httplib::Response& res,
                                           const std::function<void(Database&)>& fn) { WithDb(res, fn); },
                         .make_nonce = [] { return RandomHex(16); },
                         .token = token,
                         .reviewer = options.reviewer});
}

ReviewServer::ReviewServer(const std::filesystem::path& db_path, const ServeOptions& options)
    : impl_(std::make_unique<Impl>()) {
  if (!IsLoopbackHost(options.host) && !options.allow_remote) {
    throw Error("remote_bind",
                "refusing to listen on '" + options.host +
                    "', which is not a loopback address: anyone who can reach it could read "
                    "the clips and, with the page's token, write decisions. Pass "
                    "--allow-remote to listen there anyway",
                {.field = "host"});
  }
  impl_->options = options;
  impl_->db = std::make_unique<Database>(db_path, Database::OpenMode::kExisting);
  impl_->Routes();
}

ReviewServer::~ReviewServer() { Stop(); }

int ReviewServer::Start() {
  impl_->Bind();
  impl_->thread = std::thread([this] { impl_->http.listen_after_bind(); });
  // Stop() before the loop runs would be lost, so return once it runs.
  for (int i = 0; i < 2000 && !impl_->http.is_running(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return impl_->port;
}

void ReviewServer::Serve(const std::function<void(int port)>& on_listening) {
  impl_->Bind();
  if (on_listening) on_listening(impl_->port);
  impl_->http.listen_after_bind();
}

void ReviewServer::Stop() {
  if (!impl_) return;
  impl_->http.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

int ReviewServer::port() const { return impl_->port; }
const std::string& ReviewServer::token() const { return impl_->token; }
std::string ReviewServer::Origin() const {
  return "http://" + impl_->UrlHost() + ":" + std::to_string(impl_->port);
}

}  // namespace doasido::review
