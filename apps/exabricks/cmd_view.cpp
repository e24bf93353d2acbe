// exabricks view: the interactive viewer, served to a browser (see docs/viewer.md).
#include "commands.h"
#include "common.h"
#include "scene_options.h"

#include "exabricks/core/log.h"
#include "exabricks/render/renderer.h"

#ifdef EXABRICKS_HAVE_VIEWER
#include "view/server.h"

#include <csignal>
#include <cstdio>
#include <iostream>
#include <pthread.h>
#include <thread>
#include <unistd.h>
#endif

namespace exa::cli {
namespace {

#ifdef EXABRICKS_HAVE_VIEWER
/// This machine's name, for the SSH hint ("localhost" where it has none).
std::string hostName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "localhost";
  return name;
}
#endif

struct ViewCmdOptions {
  RenderOptions scene;
  std::string host = "127.0.0.1";
  int port = 8765;
  std::string token;
};

/// Passes the viewer refines to when neither the options nor a scene file say.
constexpr int kDefaultViewerPasses = 8;

#ifdef EXABRICKS_HAVE_VIEWER
void run(const ViewCmdOptions& o, const CLI::App& cmd) {
  // Ctrl-C and SIGTERM are taken by one thread (sigwait) that stops the server cleanly; every
  // thread started from here on inherits the blocked mask.
  sigset_t stopSignals;
  sigemptyset(&stopSignals);
  sigaddset(&stopSignals, SIGINT);
  sigaddset(&stopSignals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);

  if (o.port < 0 || o.port > 65535) failUsage("--port must be in 0..65535 (0: any free port)");
  if (!o.token.empty() && o.token.size() < 16) failUsage("--token must have at least 16 characters");
  view::checkListenAddress(o.host, o.port); // before the dataset loads: a taken port fails at once
  SceneDocument doc = sceneFromOptions(o.scene, cmd);
  if (!cmd.count("--spp") && o.scene.sceneFile.empty()) doc.frame.samplesPerPixel = kDefaultViewerPasses;

  Timer loadTimer;
  LoadOptions lo = o.scene.in.loadOptions(false);
  lo.fields.clear(); // every field: the page can switch between them
  auto model = std::make_shared<const Model>(loadModel(doc.input, lo));
  const DatasetInfo dataset = DatasetInfo::of(*model);
  applyDataDefaults(o.scene, cmd, doc.scene, *model, dataset);
  {
    Renderer framing(*model, dataset);
    framing.setScene(doc.scene);
    doc.frame.camera = cameraFromOptions(o.scene, cmd, doc, *model, framing.visibleBounds());
  }
  doc.frame.validate();
  doc.hasCamera = true;
  doc = withAbsolutePaths(doc);
  logInfo(strCat("loaded and built in ", loadTimer.seconds(), " s"));

  view::ViewContent content;
  content.model = model;
  content.dataset = dataset;
  content.input = doc.input;
  content.name = datasetLabel(o.scene.in.input);
  content.initial = doc;
  view::ServerOptions options;
  options.host = o.host;
  options.port = o.port;
  options.token = o.token;
  view::Server server(std::move(content), options);
  server.bind();

  std::cout << server.url() << std::endl;
  if (logLevel() >= LogLevel::Warning) {
    std::fprintf(stderr,
                 "exabricks: viewing %s at %s\n"
                 "  from another machine: ssh -L %d:localhost:%d %s, then open the address there\n"
                 "  Ctrl-C stops the viewer\n",
                 o.scene.in.name().c_str(), server.url().c_str(), server.port(), server.port(), hostName().c_str());
  }
  std::thread signalWaiter([&] {
    int signal = 0;
    sigwait(&stopSignals, &signal);
    if (signal == SIGINT || signal == SIGTERM) server.stop();
  });
  server.run();
  server.stop();
  pthread_kill(signalWaiter.native_handle(), SIGTERM); // wakes the waiter when the server ended by itself
  signalWaiter.join();
  logNote("viewer stopped");
}
#else
void run(const ViewCmdOptions&, const CLI::App&) {
  fail("this exabricks was built without the viewer: install pkg-config, libcpp-httplib-dev and libturbojpeg0-dev "
       "and build again");
}
#endif

} // namespace

void addView(CLI::App& app) {
  auto o = std::make_shared<ViewCmdOptions>();
  CLI::App* cmd = app.add_subcommand("view", "Explore a dataset interactively in a web browser");
  o->scene.add(*cmd);
  cmd->add_option("--port", o->port, "Port to listen on (0: any free port)")->capture_default_str();
  cmd->add_option("--host", o->host, "Address to listen on (127.0.0.1: this machine only)")->capture_default_str();
  cmd->add_option("--token", o->token, "Access token (default: a random one, printed with the address)");
  cmd->callback([o, cmd] { run(*o, *cmd); });
}

} // namespace exa::cli
