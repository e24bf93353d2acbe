#include "server.h"

#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/documents/image.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/scene_vocabulary.h"
#include "exabricks/render/transfer_function.h"

#include "jobs.h"
#include "movie.h"
#include "pictures.h"
#include "session.h"
#include "steps.h"
#include "web_assets.h"

#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <netdb.h>
#include <random>
#include <sys/socket.h>
#include <unistd.h>

namespace exa::view {

using json = nlohmann::json;

namespace {

/// Compares in time independent of where the strings differ.
bool sameToken(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

/// A client error: the status and the message the page shows.
struct RequestError {
  int status;
  std::string message;
};

[[noreturn]] void reject(int status, const std::string& message) { throw RequestError{status, message}; }

void sendJson(httplib::Response& res, const json& j, int status = 200) {
  res.status = status;
  res.set_content(j.dump(), "application/json");
}

void sendError(httplib::Response& res, int status, const std::string& message) {
  sendJson(res, json{{"error", message}}, status);
}

json parseBody(const httplib::Request& req) {
  try {
    return json::parse(req.body);
  } catch (const json::exception& e) {
    reject(400, std::string("the request body is not valid JSON: ") + e.what());
  }
}

double numberParam(const httplib::Request& req, const char* name, double fallback) {
  if (!req.has_param(name)) return fallback;
  double v = 0;
  if (!parseFiniteNumber(req.get_param_value(name), v)) reject(400, strCat("parameter '", name, "' is not a number"));
  return v;
}

/// The listening socket's options: SO_REUSEADDR only (a restarted viewer binds its port while
/// old connections linger), never SO_REUSEPORT, which would let a second server bind the same
/// port and share its connections.
void listenSocketOptions(int sock) {
  int yes = 1;
  setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
}

/// Why host:port cannot be bound, found by binding a probe socket the same way: the errno of
/// the failed bind (0 when the probe binds, -1 when the address does not resolve) and its text.
std::pair<int, std::string> bindProblem(const std::string& host, int port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* found = nullptr;
  if (const int rc = getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found); rc != 0)
    return {-1, strCat("cannot resolve the address: ", gai_strerror(rc))};
  std::pair<int, std::string> problem{0, ""};
  for (addrinfo* a = found; a; a = a->ai_next) {
    const int sock = ::socket(a->ai_family, a->ai_socktype, a->ai_protocol);
    if (sock < 0) {
      problem = {errno, std::strerror(errno)};
      continue;
    }
    listenSocketOptions(sock);
    const bool bound = ::bind(sock, a->ai_addr, a->ai_addrlen) == 0;
    if (!bound) problem = {errno, std::strerror(errno)};
    ::close(sock);
    if (bound) {
      problem = {0, ""};
      break;
    }
  }
  freeaddrinfo(found);
  return problem;
}

json rangeJson(const range1f& r) {
  if (r.empty()) return json::array({nullptr, nullptr});
  return json::array({r.lower, r.upper});
}

} // namespace

struct Server::Impl {
  ViewContent content;
  ServerOptions options;
  std::string token;
  httplib::Server http;
  std::unique_ptr<Session> session;
  std::unique_ptr<ViewSteps> steps;
  std::unique_ptr<MovieMaker> movies;
  std::unique_ptr<PictureMaker> pictures;
  std::atomic<int> streams{0};
  std::atomic<int> snapshotWaits{0};
  std::atomic<bool> stopping{false};
  int port = 0;

  /// A scene document from a request: parsed, its meshes resolved to the meshes loaded at start,
  /// its settings and fields checked, sizes bounded. Throws RequestError.
  SceneDocument documentFrom(const std::string& text, const char* what, bool* hasCamera = nullptr) {
    SceneDocument doc;
    try {
      doc = readSceneJson(text, what);
    } catch (const Error& e) {
      reject(400, e.what());
    }
    if (hasCamera) *hasCamera = doc.hasCamera;
    if (!doc.hasCamera) doc.frame.camera = content.initial.frame.camera;
    const StepView step = steps->current();
    doc.input = step.input;
    for (SceneMesh& m : doc.scene.meshes) {
      if (m.mesh) continue; // given inline
      const auto& known = content.initial.scene.meshes;
      const auto it =
          std::find_if(known.begin(), known.end(), [&](const SceneMesh& k) { return k.source == m.source; });
      if (it == known.end())
        reject(400, strCat(what, ": mesh '", m.source,
                           "' was not given when the viewer started (the viewer reads no file a request names; "
                           "start it with --mesh ",
                           m.source, ")"));
      m.mesh = it->mesh;
    }
    const Frame& f = doc.frame;
    if (f.width < 1 || f.height < 1 || f.width > options.maxImageSide || f.height > options.maxImageSide)
      reject(400, strCat(what, ": image size ", f.width, "x", f.height, " is outside 1..", options.maxImageSide,
                         " per side"));
    if (f.samplesPerPixel < 1 || f.samplesPerPixel > options.maxSamplesPerPixel)
      reject(400,
             strCat(what, ": samples per pixel ", f.samplesPerPixel, " is outside 1..", options.maxSamplesPerPixel));
    try {
      doc.scene.validate();
      f.validate();
      const Model& model = *step.model;
      auto check = [&](const std::string& field) {
        if (!field.empty()) model.requireField(field);
      };
      for (const VolumeLayer& l : doc.scene.layers)
        check(l.field);
      check(doc.scene.iso.field);
      check(doc.scene.iso.colorField);
    } catch (const Error& e) {
      reject(400, strCat(what, ": ", e.what()));
    }
    return doc;
  }

  json info() const {
    const StepView step = steps->current();
    const Model& model = *step.model;
    json j;
    j["name"] = content.name;
    j["input"] = step.input;
    j["step"] = step.index;
    j["steps"] = steps->size();
    j["simulation"] = simulationJson(model.simulation);
    j["can_encode_movies"] = MovieMaker::canEncode();
    j["nan_as_holes"] = steps->loadOptions().nonFinite == NonFinite::Holes;
    json fields = json::array();
    for (size_t i = 0; i < model.fieldNames.size(); ++i)
      fields.push_back({{"name", model.fieldNames[i]},
                        {"units", model.unitsOf(int(i))},
                        {"range", rangeJson(step.dataset.valueRanges.at(i))}});
    j["fields"] = fields;
    j["default_field"] = model.fieldNames.at(size_t(model.requireField("")));
    const box3i cb = model.cellBounds();
    const vec3d lo = model.world.toWorld(vec3d(cb.lower)), hi = model.world.toWorld(vec3d(cb.upper));
    j["bounds"] = {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z};
    const ModelSummary summary = summarize(model);
    j["cells"] = summary.cells;
    j["regions"] = summary.regions;
    json levels = json::array();
    for (const ModelSummary::Level& l : summary.levels) {
      const vec3d w = model.world.scale * double(1u << l.level);
      levels.push_back(json{{"level", l.level}, {"cell_width", {w.x, w.y, w.z}}, {"cells", l.cells}});
    }
    j["levels"] = levels;
    json maps = json::object();
    for (const std::string& name : builtinColorMapNames()) {
      const ColorMap map = builtinColorMap(name);
      json samples = json::array();
      for (int i = 0; i < 32; ++i) {
        const vec3f c = linearToSrgb(map.at(float(i) / 31.f));
        samples.push_back({c.x, c.y, c.z});
      }
      maps[name] = samples;
    }
    j["colormaps"] = maps;
    j["document"] = json::parse(writeSceneJson(content.initial));
    j["default_opacity_scale"] = step.dataset.defaultOpacityScale;
    j["limits"] = {{"max_image_side", options.maxImageSide},
                   {"max_samples_per_pixel", options.maxSamplesPerPixel},
                   {"max_request_bytes", options.maxRequestBytes}};
    return j;
  }

  /// Counts of the field's values over `bins` equal steps of the normalised value.
  json histogram(const httplib::Request& req) const {
    const StepView step = steps->current();
    const Model& model = *step.model;
    if (!req.has_param("field")) reject(400, "histogram: parameter 'field' is missing");
    const std::string name = req.get_param_value("field");
    const int field = model.fieldIndex(name);
    if (field < 0) reject(400, strCat("histogram: unknown field '", name, "'"));
    const double bins = numberParam(req, "bins", 128);
    if (!(bins >= 1 && bins <= 4096) || bins != std::floor(bins)) reject(400, "histogram: bins must be in 1..4096");
    const range1f data = step.dataset.valueRanges.at(size_t(field));
    const double lo = numberParam(req, "lo", data.empty() ? 0.0 : data.lower);
    const double hi = numberParam(req, "hi", data.empty() ? 1.0 : data.upper);
    const bool logScale = req.has_param("log") && req.get_param_value("log") == "1";
    if (!(lo < hi)) reject(400, "histogram: lo must be below hi");
    if (logScale && !(lo > 0)) reject(400, "histogram: a log histogram needs lo > 0");
    TransferFunction tf;
    tf.valueRange = range1f{float(lo), float(hi)};
    tf.logScale = logScale;
    std::vector<uint64_t> counts(size_t(bins), 0);
    uint64_t below = 0, above = 0, none = 0;
    const float flo = float(lo), fhi = float(hi);
    for (float v : model.fieldValues[size_t(field)]) {
      if (!std::isfinite(v) || (logScale && !(v > 0.f))) {
        ++none;
        continue;
      }
      if (v < flo) {
        ++below;
        continue;
      }
      if (v > fhi) {
        ++above;
        continue;
      }
      const float t = tf.normalize(v);
      counts[std::min(size_t(t * float(bins)), counts.size() - 1)]++;
    }
    return {{"counts", counts}, {"below", below}, {"above", above}, {"excluded", none},
            {"lo", lo},         {"hi", hi},       {"log", logScale}};
  }

  bool authorised(const httplib::Request& req) const {
    if (req.has_param("token") && sameToken(req.get_param_value("token"), token)) return true;
    if (req.has_header("X-Exabricks-Token") && sameToken(req.get_header_value("X-Exabricks-Token"), token)) return true;
    const std::string cookies = req.get_header_value("Cookie");
    const std::string key = strCat(cookieName(), "=");
    for (size_t at = cookies.find(key); at != std::string::npos; at = cookies.find(key, at + 1)) {
      if (at > 0 && cookies[at - 1] != ' ' && cookies[at - 1] != ';') continue;
      const size_t begin = at + key.size();
      const size_t end = cookies.find(';', begin);
      if (sameToken(cookies.substr(begin, end == std::string::npos ? std::string::npos : end - begin), token))
        return true;
    }
    return false;
  }

  /// One cookie per port: viewers on other ports of the same host keep their own.
  std::string cookieName() const { return strCat("exabricks_token_", port); }

  void routes();
  void seriesRoutes();
  void movieRoutes();
  void pictureRoutes();
};

void Server::Impl::routes() {
  // Every request needs the token; the page's own request sets the cookie its assets and API
  // calls then carry.
  http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (authorised(req)) return httplib::Server::HandlerResponse::Unhandled;
    sendError(res, 403, "a valid token is required: open the address the viewer printed (it ends in ?token=...)");
    return httplib::Server::HandlerResponse::Handled;
  });
  http.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
    try {
      std::rethrow_exception(ep);
    } catch (const RequestError& e) {
      sendError(res, e.status, e.message);
    } catch (const std::bad_alloc&) {
      sendError(res, 503, "out of memory");
    } catch (const std::exception& e) {
      sendError(res, 500, e.what());
    } catch (...) {
      sendError(res, 500, "internal error");
    }
  });
  http.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;
    const char* what = res.status == 404   ? "no such resource"
                       : res.status == 413 ? "the request is too large"
                       : res.status == 400 ? "malformed request"
                                           : "request refused";
    sendError(res, res.status, what);
  });

  auto asset = [this](const WebAsset& a) {
    return [this, &a](const httplib::Request& req, httplib::Response& res) {
      if (req.has_param("token"))
        res.set_header("Set-Cookie", strCat(cookieName(), "=", token, "; Path=/; HttpOnly; SameSite=Strict"));
      res.set_header("Cache-Control", "no-store");
      res.set_content(std::string(a.data, a.size), a.mime);
    };
  };
  for (const WebAsset& a : webAssets()) {
    http.Get(a.path, asset(a));
    if (std::strcmp(a.path, "/index.html") == 0) http.Get("/", asset(a));
  }

  http.Get("/api/info", [this](const httplib::Request&, httplib::Response& res) { sendJson(res, info()); });
  http.Get("/api/histogram",
           [this](const httplib::Request& req, httplib::Response& res) { sendJson(res, histogram(req)); });

  http.Post("/api/render", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = parseBody(req);
    if (!body.is_object() || !body.contains("scene") || !body["scene"].is_object())
      reject(400, "render: the body must be an object with a \"scene\" object (and optionally \"interactive\")");
    for (const auto& [key, value] : body.items())
      if (key != "scene" && key != "interactive") reject(400, strCat("render: unknown key '", key, "'"));
    bool interactive = false;
    if (body.contains("interactive")) {
      if (!body["interactive"].is_boolean()) reject(400, "render: \"interactive\" must be true or false");
      interactive = body["interactive"].get<bool>();
    }
    const SceneDocument doc = documentFrom(body["scene"].dump(), "render scene");
    const uint64_t id = session->submit(doc, interactive);
    sendJson(res, {{"request", id}});
  });

  // Frames as a stream of records: u32 header length, header JSON, u32 JPEG length, JPEG
  // (lengths little-endian). Only the newest frame is sent: a slow page skips frames.
  http.Get("/api/stream", [this](const httplib::Request& req, httplib::Response& res) {
    if (streams.fetch_add(1) >= options.maxStreams) {
      streams.fetch_sub(1);
      reject(429, strCat("too many open frame streams (at most ", options.maxStreams, ")"));
    }
    uint64_t after = 0;
    if (req.has_param("after")) after = uint64_t(std::max(0.0, numberParam(req, "after", 0)));
    res.set_header("Cache-Control", "no-store");
    res.set_chunked_content_provider(
        "application/octet-stream",
        [this, after](size_t, httplib::DataSink& sink) mutable {
          auto frame = session->waitFrame(after, 2000);
          if (stopping) {
            sink.done();
            return true;
          }
          if (!sink.is_writable()) return false;
          json header;
          std::string image;
          if (frame) {
            const FrameInfo& i = frame->info;
            after = i.sequence;
            header = {{"request", i.request},
                      {"sequence", i.sequence},
                      {"draft", i.draft},
                      {"final", i.final},
                      {"width", i.width},
                      {"height", i.height},
                      {"passes", i.passes},
                      {"target_passes", i.targetPasses},
                      {"render_seconds", i.renderSeconds},
                      {"since_request", i.sinceRequest},
                      {"samples", i.samples},
                      {"samples_per_second", i.samplesPerSecond},
                      {"visible_regions", i.visibleRegions},
                      {"regions", i.regions}};
            if (!frame->error.empty()) header["error"] = frame->error;
            image = frame->jpeg;
          } else {
            header = {{"keepalive", true}}; // lets a closed page be noticed
          }
          const std::string text = header.dump();
          auto u32 = [](size_t n) {
            const uint32_t v = uint32_t(n);
            return std::string{char(v & 255u), char((v >> 8) & 255u), char((v >> 16) & 255u), char((v >> 24) & 255u)};
          };
          const std::string record = u32(text.size()) + text + u32(image.size()) + image;
          return sink.write(record.data(), record.size());
        },
        [this](bool) { streams.fetch_sub(1); });
  });

  // The full-resolution image, losslessly: the latest one, or (with request=N, as the page's Save
  // PNG asks) request N's once it is refined to its samples per pixel.
  http.Get("/api/snapshot.png", [this](const httplib::Request& req, httplib::Response& res) {
    Session::Snapshot s;
    if (req.has_param("request")) {
      const double id = numberParam(req, "request", 0);
      if (!(id >= 1 && id == std::floor(id) && id < 9.0e15)) reject(400, "snapshot: request must be a request number");
      if (snapshotWaits.fetch_add(1) >= 2) {
        snapshotWaits.fetch_sub(1);
        reject(429, "snapshot: two saves are already waiting for their images");
      }
      const Session::Wait wait = session->waitSnapshot(uint64_t(id), 600 * 1000, s);
      snapshotWaits.fetch_sub(1);
      switch (wait) {
      case Session::Wait::Ready:
        break;
      case Session::Wait::Superseded:
        reject(409, "the view changed before its image was refined: save again");
      case Session::Wait::Draft:
        reject(409, "the view is still being dragged: it has no full-resolution image yet");
      case Session::Wait::Failed:
        reject(409, "the view could not be rendered (see the error shown)");
      case Session::Wait::Unknown:
        reject(404, strCat("snapshot: no request ", uint64_t(id)));
      case Session::Wait::TimedOut:
        reject(503, "the image is still refining after 10 minutes: save again later");
      case Session::Wait::Stopped:
        reject(503, "the viewer is stopping");
      }
    } else {
      s = session->snapshot();
      if (!s.image) reject(404, "no full-resolution image yet");
    }
    const std::vector<unsigned char> png = encodePng(*s.image, s.keepAlpha, s.background);
    res.set_header("X-Exabricks-Request", std::to_string(s.request));
    res.set_header("X-Exabricks-Passes", std::to_string(s.passes));
    res.set_header("Cache-Control", "no-store");
    res.set_content(std::string(png.begin(), png.end()), "image/png");
  });

  // The first picture's transfer function for a field (docs/rendering.md, "The first picture"):
  // what the page adopts when the user switches fields, so that the new field gets its own
  // mapping, range and opacity instead of the old field's.
  http.Get("/api/first-picture", [this](const httplib::Request& req, httplib::Response& res) {
    const StepView step = steps->current();
    const Model& model = *step.model;
    if (!req.has_param("field")) reject(400, "first-picture: parameter 'field' is missing");
    const std::string name = req.get_param_value("field");
    const int field = model.fieldIndex(name);
    if (field < 0) reject(400, strCat("first-picture: unknown field '", name, "'"));
    const DefaultChoices c = adaptTransferFunction(model, step.dataset, field, defaultTransferFunction(), true, true);
    sendJson(res,
             {{"field", name}, {"transfer_function", json::parse(transferFunctionJson(c.tf))}, {"notes", c.notes}});
  });

  // The scalar settings of scene files: key, type, default, range, choices and help.
  http.Get("/api/vocabulary",
           [](const httplib::Request&, httplib::Response& res) { sendJson(res, json::parse(sceneVocabularyJson())); });
  // The scene in effect, in the form `exabricks render --scene` reads.
  http.Get("/api/scene", [this](const httplib::Request&, httplib::Response& res) {
    const std::optional<SceneDocument> doc = session->current();
    SceneDocument d = doc ? *doc : content.initial;
    d.hasCamera = true;
    res.set_header("Cache-Control", "no-store");
    res.set_content(writeSceneJson(d), "application/json");
  });
  // An uploaded scene file: checked and returned in full, for the page to adopt.
  http.Post("/api/scene", [this](const httplib::Request& req, httplib::Response& res) {
    bool hasCamera = false;
    SceneDocument doc = documentFrom(req.body, "uploaded scene", &hasCamera);
    doc.hasCamera = true;
    sendJson(res, {{"document", json::parse(writeSceneJson(doc))}, {"has_camera", hasCamera}});
  });
  seriesRoutes();
  movieRoutes();
  pictureRoutes();
  // An uploaded transfer function (ParaView preset or exabricks JSON), returned in exabricks
  // form; a preset's points are rescaled to the data's range as ParaView applies presets.
  http.Post("/api/transfer-function", [](const httplib::Request& req, httplib::Response& res) {
    bool preset = false;
    TransferFunction tf;
    try {
      tf = parseTransferFunction(req.body, "uploaded transfer function", &preset);
    } catch (const Error& e) {
      reject(400, e.what());
    }
    if (preset) {
      tf.valueRange = range1f();
      tf.opacityScale = 0.f;
    }
    sendJson(
        res,
        {{"transfer_function", json::parse(transferFunctionJson(tf))}, {"preset", preset}, {"name", tf.colorMap.name}});
  });
}

/// An integer from a JSON body, or a 400 naming the key.
static int intOf(const json& body, const char* key, const char* what) {
  const json& v = body.at(key);
  if (!v.is_number_integer() && !(v.is_number() && v.get<double>() == std::floor(v.get<double>())))
    reject(400, strCat(what, ": \"", key, "\" must be a whole number"));
  const double d = v.get<double>();
  if (!(d >= -2.0e9 && d <= 2.0e9)) reject(400, strCat(what, ": \"", key, "\" is out of range"));
  return int(d);
}

/// The series' routes: its steps (names, simulation time and cycle once loaded, the current one,
/// with ?field=F the field's range over all steps) and the choice of step among those given at
/// start; the step's scene renders at once.
void Server::Impl::seriesRoutes() {
  http.Get("/api/series", [this](const httplib::Request& req, httplib::Response& res) {
    json j = steps->describe();
    if (req.has_param("field")) {
      const std::string name = req.get_param_value("field");
      if (steps->current().model->fieldIndex(name) < 0) reject(400, strCat("series: unknown field '", name, "'"));
      try {
        j["range"] = rangeJson(steps->rangeOf(name));
      } catch (const Error& e) {
        reject(400, strCat("series: ", e.what()));
      }
      j["field"] = name;
    }
    sendJson(res, j);
  });
  http.Post("/api/step", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = parseBody(req);
    if (!body.is_object() || !body.contains("index"))
      reject(400, "step: the body must be an object with the step's \"index\" (from 0)");
    for (const auto& [key, value] : body.items())
      if (key != "index") reject(400, strCat("step: unknown key '", key, "'"));
    const int index = intOf(body, "index", "step");
    if (index < 0 || index >= steps->size())
      reject(400, strCat("step: index ", index, " is outside the steps 0..", steps->size() - 1, " (", steps->size(),
                         steps->size() == 1 ? " step" : " steps", " given when the viewer started)"));
    if (index == steps->current().index) {
      sendJson(res, steps->describe());
      return;
    }
    StepView step;
    try {
      step = steps->select(index);
    } catch (const Error& e) {
      reject(500, strCat("step ", index, " could not be loaded: ", e.what()));
    }
    LegendText legends;
    legends.dataset = legendDatasetLabel(step.input);
    session->setModel(step.model, step.dataset, std::move(legends));
    SceneDocument doc = session->current().value_or(content.initial);
    doc.input = step.input;
    session->submit(doc, false);
    sendJson(res, steps->describe());
  });
  // NaN and infinite values as holes, or refused: the current step is read again that way (and
  // every later one); a step that cannot be read so stays as it was, with the reason.
  http.Post("/api/holes", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = parseBody(req);
    if (!body.is_object() || !body.contains("holes") || !body["holes"].is_boolean() || body.size() != 1)
      reject(400, "holes: the body must be {\"holes\": true} or {\"holes\": false}");
    LoadReport report;
    StepView step;
    try {
      step = steps->setNonFinite(body["holes"].get<bool>() ? NonFinite::Holes : NonFinite::Refuse, &report);
    } catch (const Error& e) {
      reject(400, strCat("holes: ", e.what()));
    }
    LegendText legends;
    legends.dataset = legendDatasetLabel(step.input);
    session->setModel(step.model, step.dataset, std::move(legends));
    SceneDocument doc = session->current().value_or(content.initial);
    doc.input = step.input;
    session->submit(doc, false);
    json j = info();
    json fields = json::object();
    for (const auto& [field, count] : report.nonFinite)
      fields[field] = count;
    j["holes"] = {{"cells", report.holes}, {"fields", fields}};
    sendJson(res, j);
  });
}

/// The movie's routes: start one with the scene on screen, follow and cancel it, and fetch the
/// finished file by the id the server made.
void Server::Impl::movieRoutes() {
  http.Post("/api/movie", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = parseBody(req);
    if (!body.is_object() || !body.contains("scene") || !body["scene"].is_object())
      reject(400, "movie: the body must be an object with a \"scene\" object (and optionally \"fps\", \"frames\")");
    MovieInput in;
    for (const auto& [key, value] : body.items())
      if (key != "scene" && key != "fps" && key != "frames") reject(400, strCat("movie: unknown key '", key, "'"));
    if (body.contains("fps")) {
      if (!body["fps"].is_number() || !(body["fps"].get<double>() > 0 && body["fps"].get<double>() <= 120))
        reject(400, "movie: \"fps\" must be a number in (0, 120]");
      in.fps = body["fps"].get<double>();
    }
    if (body.contains("frames")) {
      in.orbitFrames = intOf(body, "frames", "movie");
      if (in.orbitFrames < 1 || in.orbitFrames > 3600) reject(400, "movie: \"frames\" must be in 1..3600");
    }
    in.doc = documentFrom(body["scene"].dump(), "movie scene");
    in.current = steps->current();
    if (steps->isSeries()) {
      in.steps = steps->paths();
      in.series = content.series->options();
      in.series.load = steps->loadOptions(); // NaN as holes as the page chose
    }
    in.series.renderer = content.rendererOptions;
    if (!MovieMaker::canEncode())
      reject(503, "ffmpeg is not installed on the machine the viewer runs on, so it cannot encode movies: install "
                  "ffmpeg and start the viewer again (or use `exabricks movie` with a folder for the frames)");
    if (movies->busy()) reject(409, "a movie is already being made: wait for it or cancel it");
    const std::string id = movies->start(std::move(in));
    sendJson(res, movies->status(id));
  });
  auto idOf = [](const httplib::Request& req, const char* what) {
    if (!req.has_param("id")) reject(400, strCat(what, ": parameter 'id' is missing"));
    return req.get_param_value("id");
  };
  http.Get("/api/movie", [this, idOf](const httplib::Request& req, httplib::Response& res) {
    const json j = movies->status(idOf(req, "movie"));
    if (j.is_null()) reject(404, "movie: no movie has that id");
    sendJson(res, j);
  });
  http.Post("/api/movie/cancel", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = parseBody(req);
    if (!body.is_object() || !body.contains("id") || !body["id"].is_string())
      reject(400, "movie cancel: the body must be an object with the movie's \"id\"");
    const std::string id = body["id"].get<std::string>();
    if (!movies->cancel(id)) reject(404, "movie cancel: no movie has that id");
    sendJson(res, movies->status(id));
  });
  http.Get("/api/movie/file", [this, idOf](const httplib::Request& req, httplib::Response& res) {
    const std::string id = idOf(req, "movie file");
    const json j = movies->status(id);
    if (j.is_null()) reject(404, "movie file: no movie has that id");
    const std::string path = movies->file(id);
    if (path.empty()) reject(409, strCat("movie file: the movie is ", j["state"].get<std::string>(), ", not done"));
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) reject(500, "movie file: cannot read the movie");
    res.set_header("Content-Disposition", "attachment; filename=\"exabricks.mp4\"");
    res.set_header("Cache-Control", "no-store");
    res.set_content(std::move(bytes), "video/mp4");
  });
}

void Server::Impl::pictureRoutes() {
  http.Post("/api/picture", [this](const httplib::Request& req, httplib::Response& res) {
    json body = parseBody(req);
    if (!body.is_object() || !body.contains("scene") || !body["scene"].is_object())
      reject(400, "picture: the body must be an object with a \"scene\" object and \"width\", \"height\", "
                  "\"spp\" and \"format\" (png, png16, exr or pfm)");
    for (const auto& [key, value] : body.items())
      if (key != "scene" && key != "width" && key != "height" && key != "spp" && key != "format")
        reject(400, strCat("picture: unknown key '", key, "'"));
    json& frame = body["scene"]["frame"];
    if (!frame.is_object()) frame = json::object();
    frame["width"] = intOf(body, "width", "picture");
    frame["height"] = intOf(body, "height", "picture");
    frame["samples_per_pixel"] = intOf(body, "spp", "picture");
    const std::string format = body.value("format", std::string("png"));
    PictureInput in;
    if (format == "png" || format == "png16" || format == "exr" || format == "pfm")
      in.format = format == "png16" ? ImageFormat::Png16
                  : format == "exr" ? ImageFormat::Exr
                  : format == "pfm" ? ImageFormat::Pfm
                                    : ImageFormat::Png;
    else
      reject(400, strCat("picture: format is '", format, "' (choose from: png, png16, exr, pfm)"));
    in.doc = documentFrom(body["scene"].dump(), "picture scene");
    in.step = steps->current();
    in.legends.dataset = legendDatasetLabel(in.step.input);
    in.renderer = content.rendererOptions;
    const Model& model = *in.step.model;
    const std::string& field = model.fieldNames[size_t(
        model.requireField(in.doc.scene.layers.empty() ? std::string() : in.doc.scene.layers[0].field))];
    in.name = pictureName(in.step.input.empty() ? "exabricks" : in.step.input, field, in.doc.frame.width,
                          in.doc.frame.height, in.format);
    if (pictures->busy()) reject(409, "a picture is already being rendered: wait for it or cancel it");
    const std::string id = pictures->start(std::move(in));
    sendJson(res, pictures->status(id));
  });
  auto idOf = [](const httplib::Request& req, const char* what) {
    if (!req.has_param("id")) reject(400, strCat(what, ": parameter 'id' is missing"));
    return req.get_param_value("id");
  };
  http.Get("/api/picture", [this, idOf](const httplib::Request& req, httplib::Response& res) {
    const json j = pictures->status(idOf(req, "picture"));
    if (j.is_null()) reject(404, "picture: no picture has that id");
    sendJson(res, j);
  });
  http.Post("/api/picture/cancel", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = parseBody(req);
    if (!body.is_object() || !body.contains("id") || !body["id"].is_string())
      reject(400, "picture cancel: the body must be an object with the picture's \"id\"");
    const std::string id = body["id"].get<std::string>();
    if (!pictures->cancel(id)) reject(404, "picture cancel: no picture has that id");
    sendJson(res, pictures->status(id));
  });
  http.Get("/api/picture/file", [this, idOf](const httplib::Request& req, httplib::Response& res) {
    const std::string id = idOf(req, "picture file");
    const json j = pictures->status(id);
    if (j.is_null()) reject(404, "picture file: no picture has that id");
    const auto [path, name] = pictures->file(id);
    if (path.empty()) reject(409, strCat("picture file: the picture is ", j["state"].get<std::string>(), ", not done"));
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) reject(500, "picture file: cannot read the picture");
    res.set_header("Content-Disposition", strCat("attachment; filename=\"", name, "\""));
    res.set_header("Cache-Control", "no-store");
    const bool png = name.size() > 4 && name.substr(name.size() - 4) == ".png";
    res.set_content(std::move(bytes), png ? "image/png" : "application/octet-stream");
  });
}

Server::Server(ViewContent content, ServerOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->content = std::move(content);
  impl_->options = std::move(options);
  impl_->token = impl_->options.token.empty() ? randomHex(48) : impl_->options.token;
}

Server::~Server() { stop(); }

void Server::bind() {
  Impl& s = *impl_;
  if (!s.content.model) fail("viewer: no dataset");
  s.http.set_payload_max_length(s.options.maxRequestBytes);
  s.http.set_read_timeout(10, 0);
  s.http.set_write_timeout(10, 0);
  s.http.set_keep_alive_timeout(1); // idle connections close soon, so that stopping is quick
  s.http.set_tcp_nodelay(true);
  s.http.set_socket_options(listenSocketOptions);
  // Streams hold a worker each; leave room for the API requests beside them.
  const size_t workers = size_t(std::max(4, s.options.maxStreams + 4));
  s.http.new_task_queue = [workers] { return new httplib::ThreadPool(workers); };
  s.routes();
  if (s.options.port == 0) {
    s.port = s.http.bind_to_any_port(s.options.host);
    if (s.port < 0) fail("viewer: cannot listen on ", s.options.host, " (any port)");
  } else {
    if (!s.http.bind_to_port(s.options.host, s.options.port)) {
      checkListenAddress(s.options.host, s.options.port);
      fail("viewer: cannot listen on ", s.options.host, " port ", s.options.port,
           " (is it an address of this machine? --port 0 picks a free port)");
    }
    s.port = s.options.port;
  }
  s.steps = std::make_unique<ViewSteps>(StepView{0, s.content.model, s.content.dataset, s.content.input},
                                        s.content.series, s.content.steps, s.content.load);
  s.movies = std::make_unique<MovieMaker>();
  s.pictures = std::make_unique<PictureMaker>();
  LegendText legends;
  legends.dataset = s.content.name;
  s.session = std::make_unique<Session>(s.content.model, s.content.dataset, s.options, std::move(legends));
  s.session->submit(s.content.initial, false); // the first picture renders while the page loads
}

void checkListenAddress(const std::string& host, int port) {
  if (port == 0) return;
  const auto [code, why] = bindProblem(host, port);
  if (code == EADDRINUSE)
    fail("viewer: cannot listen on ", host, " port ", port, ": the port is in use (another viewer or server ",
         "listens there); choose another with --port N, or --port 0 for any free port");
  if (code != 0)
    fail("viewer: cannot listen on ", host, " port ", port, ": ", why,
         " (is it an address of this machine? --port 0 picks a free port)");
}

int Server::port() const { return impl_->port; }
const std::string& Server::token() const { return impl_->token; }

std::string Server::url() const {
  const std::string& host = impl_->options.host;
  const std::string shown = host == "0.0.0.0" || host.empty() ? "127.0.0.1" : host;
  const bool v6 = shown.find(':') != std::string::npos;
  return strCat("http://", v6 ? "[" : "", shown, v6 ? "]" : "", ":", impl_->port, "/?token=", impl_->token);
}

void Server::run() {
  if (!impl_->session) bind();
  impl_->http.listen_after_bind();
}

void Server::stop() {
  if (impl_->stopping.exchange(true)) return;
  if (impl_->session) impl_->session->stop();
  impl_->http.stop();
  impl_->movies.reset(); // a movie in progress stops; the movies' folder is removed
}

} // namespace exa::view
