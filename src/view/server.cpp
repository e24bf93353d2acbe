#include "server_impl.h"

#include "web_assets.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/log.h"

#include <cerrno>
#include <cstring>
#include <netdb.h>
#include <optional>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

namespace exa::view {

using json = nlohmann::json;

namespace {

void sendError(httplib::Response& res, int status, const std::string& message) {
  sendJson(res, json{{"error", message}}, status);
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

/// Throws exa::Error saying why the viewer could not listen on host:port (in use by another
/// server, or not an address of this machine); returns when a socket binds there now.
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

/// A record of the frame stream: u32 header length, header JSON, u32 JPEG length, JPEG (lengths
/// little-endian). The header describes the frame, or is a keep-alive where none came (it lets
/// a closed page be noticed).
std::string streamRecord(const PublishedFrame* frame) {
  json header;
  std::string image;
  if (frame) {
    const FrameInfo& i = frame->info;
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
    if (!i.data.empty()) header["data"] = i.data;
    if (!frame->error.empty()) header["error"] = frame->error;
    image = frame->jpeg;
  } else {
    header = {{"keepalive", true}};
  }
  const std::string text = header.dump();
  auto u32 = [](size_t n) {
    const uint32_t v = uint32_t(n);
    return std::string{char(v & 255u), char((v >> 8) & 255u), char((v >> 16) & 255u), char((v >> 24) & 255u)};
  };
  return u32(text.size()) + text + u32(image.size()) + image;
}

/// Refuses a snapshot of request `id` that is not ready, saying why.
void requireSnapshot(Session::Wait wait, uint64_t id) {
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
    reject(404, strCat("snapshot: no request ", id));
  case Session::Wait::TimedOut:
    reject(503, "the image is still refining after 10 minutes: save again later");
  case Session::Wait::Stopped:
    reject(503, "the viewer is stopping");
  }
}

} // namespace

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

  requestRoutes();
  frameRoutes();
  sceneRoutes();
  seriesRoutes();
  movieRoutes();
  pictureRoutes();
}

/// The data and the render requests: the dataset's description, its histogram, a scene to render.
void Server::Impl::requestRoutes() {
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
}

/// The frames: the stream of drafts and refining frames, the refined image, the first picture.
void Server::Impl::frameRoutes() {
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
          if (frame) after = frame->info.sequence;
          const std::string record = streamRecord(frame.get());
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
      requireSnapshot(wait, uint64_t(id));
    } else {
      s = session->snapshot();
      if (!s.image) reject(404, "no full-resolution image yet");
    }
    const std::vector<unsigned char> png = encodePng(*s.image, s.keepAlpha, s.background);
    res.set_header("X-Exabricks-Request", std::to_string(s.request));
    res.set_header("X-Exabricks-Passes", std::to_string(s.passes));
    res.set_header("Content-Disposition", attachment(s.image->width, s.image->height, ".png"));
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
}

/// Scenes and transfer functions: the vocabulary of scene files, the scene in effect, an uploaded
/// scene or preset.
void Server::Impl::sceneRoutes() {
  http.Get("/api/vocabulary",
           [](const httplib::Request&, httplib::Response& res) { sendJson(res, json::parse(sceneVocabularyJson())); });
  http.Get("/api/structure",
           [](const httplib::Request&, httplib::Response& res) { sendJson(res, json::parse(sceneStructureJson())); });
  // The scene in effect, in the form `exabricks render --scene` reads.
  http.Get("/api/scene", [this](const httplib::Request&, httplib::Response& res) {
    const std::optional<SceneDocument> doc = session->current();
    SceneDocument d = doc ? *doc : content.initial;
    d.hasCamera = true;
    if (d.input.empty()) d.input = kEmbeddedInput; // the default dataset
    res.set_header("Content-Disposition", attachment(d.frame.width, d.frame.height, ".json"));
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

Server::Server(ViewContent content, ServerOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->content = std::move(content);
  impl_->options = std::move(options);
  impl_->token = impl_->options.token.empty() ? randomHex(48) : impl_->options.token;
}

Server::~Server() { stop(); }

Server::Server(ServerOptions options) : Server(ViewContent(), std::move(options)) {}

void Server::Impl::listen() {
  http.set_payload_max_length(options.maxRequestBytes);
  http.set_read_timeout(10, 0);
  http.set_write_timeout(10, 0);
  http.set_keep_alive_timeout(1); // idle connections close soon, so that stopping is quick
  http.set_tcp_nodelay(true);
  http.set_socket_options(listenSocketOptions);
  // Streams hold a worker each; leave room for the API requests beside them.
  const size_t workers = size_t(std::max(4, options.maxStreams + 4));
  http.new_task_queue = [workers] { return new httplib::ThreadPool(workers); };
  routes();
  if (options.port == 0) {
    port = http.bind_to_any_port(options.host);
    if (port < 0) fail("viewer: cannot listen on ", options.host, " (any port)");
  } else {
    if (!http.bind_to_port(options.host, options.port)) {
      checkListenAddress(options.host, options.port);
      fail("viewer: cannot listen on ", options.host, " port ", options.port,
           " (is it an address of this machine? --port 0 picks a free port)");
    }
    port = options.port;
  }
}

void Server::Impl::start() {
  steps = std::make_unique<ViewSteps>(StepView{content.firstStep, content.model, content.dataset, content.input},
                                      content.series, content.steps, content.load);
  for (const auto& [index, why] : content.unreadable)
    steps->markUnreadable(index, why);
  movies = std::make_unique<MovieMaker>();
  pictures = std::make_unique<PictureMaker>();
  LegendText legends;
  legends.dataset = content.name;
  session = std::make_unique<Session>(content.model, content.dataset, options, legends, content.parts, content.budget);
  session->setParticleInput(content.input);
  if (!content.refine.empty() || content.parts) session->setDataNote(content.coarse.note());
  session->submit(content.initial, false); // the first picture renders while the page loads
  if (!content.refine.empty()) startRefining(legends);
}

void Server::bind() {
  Impl& s = *impl_;
  if (s.port <= 0) s.listen();
  if (s.content.model && !s.session) s.start();
}

void Server::show(ViewContent content) {
  Impl& s = *impl_;
  if (s.session) fail("viewer: a dataset is already shown");
  if (!content.model) fail("viewer: no dataset");
  s.content = std::move(content);
  bind();
}

/// Reads more of the dataset, step by step, on a thread of its own while less of it is shown,
/// and draws the view on screen again from each step's data. The thread is detached: a viewer
/// stopped meanwhile leaves it to the process's end, and it touches the server only while
/// `alive` says the server is there.
void Server::Impl::startRefining(const LegendText& legends) {
  std::thread([refine = content.refine, shown = content.coarse.shown, refining = refining, session = session.get(),
               steps = steps.get(), legends]() mutable {
    // The first picture first: its frame has both cores before the reads begin (for a few
    // seconds at most).
    for (int waited = 0; waited < 3000; waited += 10) {
      {
        std::lock_guard<std::mutex> lock(refining->mutex);
        if (!refining->alive) return;
        if (session->waitFrame(0, 0)) break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    for (const Refinement& step : refine) {
      std::pair<std::shared_ptr<const Model>, DatasetInfo> data;
      std::string error;
      Timer t;
      try {
        data = step.load();
      } catch (const std::exception& e) {
        error = e.what();
      }
      std::lock_guard<std::mutex> lock(refining->mutex);
      if (!refining->alive) return;
      if (!data.first) {
        logWarning(strCat("the finer levels could not be read; the view keeps ", shown, ": ", error));
        session->setDataNote(strCat(shown, " only: the finer levels could not be read (", error, ")"));
        if (std::optional<SceneDocument> doc = session->current()) session->submit(*doc, false);
        return;
      }
      logNote(strCat(step.then.shown.empty() ? "every level" : step.then.note(), ": read and built in ", t.seconds(),
                     " s; the view refines"));
      steps->refine(data.first, data.second);
      session->setModel(data.first, data.second, legends);
      session->setDataNote(step.then.note());
      shown = step.then.shown;
      if (std::optional<SceneDocument> doc = session->current()) session->submit(*doc, false);
    }
  }).detach();
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
  bind();
  if (!impl_->session) fail("viewer: no dataset");
  impl_->http.listen_after_bind();
}

void Server::stop() {
  if (impl_->stopping.exchange(true)) return;
  {
    std::lock_guard<std::mutex> lock(impl_->refining->mutex);
    impl_->refining->alive = false; // a dataset still being read is no longer shown
  }
  if (impl_->session) impl_->session->stop();
  impl_->http.stop();
  impl_->movies.reset(); // a movie in progress stops; the movies' folder is removed
}

} // namespace exa::view
