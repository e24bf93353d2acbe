// The interactive viewer: an HTTP server that renders one dataset where it lives and streams
// progressive frames to a page in the user's browser.
//
// One view per server. A request (POST /api/render) carries a whole scene document (the JSON of
// `exabricks render --scene`) and whether the user is still dragging. The render thread answers
// with a draft (reduced resolution and rate) and then, unless the user is still dragging, refines
// the full-resolution image pass by pass up to the frame's samples per pixel. A newer request
// cancels the one in flight between tiles; frames of a superseded request are never sent after
// the newer request was accepted. Frames travel as JPEG over one streaming response per page
// (GET /api/stream); the refined image is available losslessly (GET /api/snapshot.png).
//
// Safe by default: it binds to 127.0.0.1, every request needs the token printed with the URL
// (query `token=`, header `X-Exabricks-Token` or the cookie the page receives), it opens no file
// a request names (scenes and presets are uploaded; meshes must have been given at start),
// request bodies and image sizes are bounded, and malformed requests get a 4xx with a message.
#pragma once

#include "exabricks/io/load.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene.h"
#include "exabricks/workflows/series.h"
#include "exabricks/workflows/streamed.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace exa {

struct Model;

namespace view {

struct ServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;         ///< 0: any free port
  std::string token;       ///< empty: a random token
  int maxImageSide = 4096; ///< largest width or height a request may ask for
  int maxSamplesPerPixel = 1024;
  size_t maxRequestBytes = 8u << 20; ///< largest request body
  int maxStreams = 8;                ///< concurrent frame streams (pages)
  int jpegQuality = 90;              ///< drafts and refining frames
  int finalJpegQuality = 95;         ///< the frame that completes the refinement
  std::string device = "auto";       ///< where frames render: cpu, cuda, auto or portable
};

/// What a view of less than a dataset shows and what follows: the frames' `data` note.
struct DataShown {
  std::string shown; ///< empty once every level is shown
  std::string follows;
  /// "SHOWN; FOLLOWS" (or SHOWN alone), empty once every level is shown.
  std::string note() const { return shown.empty() || follows.empty() ? shown : shown + "; " + follows; }
};

/// One step of a view from less than a dataset toward all of it: what it reads and builds, and
/// what the view then shows.
struct Refinement {
  std::function<std::pair<std::shared_ptr<const Model>, DatasetInfo>()> load;
  DataShown then;
};

/// What the viewer shows: the dataset, its name, and the first scene (defaults already adapted
/// to the data, camera set). Meshes of the first scene, by their file name, are the only meshes
/// a request may name.
struct ViewContent {
  std::shared_ptr<const Model> model;
  DatasetInfo dataset;
  std::string input; ///< the dataset's path as scene files record it (absolute), or empty
  std::string name;  ///< shown on the page
  SceneDocument initial;
  /// A time series: the renderer of its steps (the first one loaded), and the steps' absolute
  /// paths as given at start, the only datasets a request may switch to. Null for one dataset.
  std::shared_ptr<SeriesRenderer> series;
  std::vector<std::string> steps;
  int firstStep = 0;                                   ///< the step shown first (the first readable one)
  std::vector<std::pair<int, std::string>> unreadable; ///< steps that could not be read, and why
  RendererOptions rendererOptions;                     ///< how movies march
  LoadOptions load;                                    ///< how the datasets were read (NaN as holes or not)
  /// Coarse levels first: `model` holds less than the whole dataset (its coarse levels, or its
  /// coarsest level merged), `coarse` says what the first frames show, and `refine` reads
  /// more of it in steps (on a thread of its own once the server is bound; each step's data then
  /// replace `model`, and the view on screen is drawn again from them).
  std::vector<Refinement> refine;
  DataShown coarse;
  /// A step larger than the memory budget: `model` holds its coarse levels (drafts and the first
  /// passes), and every still view is then drawn from all levels in these parts, one part
  /// resident at a time, within `budget` bytes (instead of `refine`).
  std::shared_ptr<StreamedStep> parts;
  uint64_t budget = 0;
};

/// Statistics of a published frame (also sent to the page with each frame).
struct FrameInfo {
  uint64_t request = 0;  ///< the request it answers
  uint64_t sequence = 0; ///< increases with every published frame
  bool draft = false;
  bool final = false; ///< the last frame of the request (target passes reached)
  int width = 0, height = 0;
  int passes = 0, targetPasses = 0;
  double renderSeconds = 0; ///< this frame's pass (or draft)
  double sinceRequest = 0;  ///< seconds from accepting the request to publishing this frame
  double samplesPerSecond = 0;
  uint64_t samples = 0;
  size_t visibleRegions = 0, regions = 0;
  std::string data; ///< what of the data the frame shows, where not all of it (coarse levels first)
};

class Server {
public:
  Server(ViewContent content, ServerOptions options);
  /// A server whose content comes later (show()): it can bind, and so print its address, while
  /// the dataset is still being read; connections wait until it runs.
  explicit Server(ServerOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Binds the socket (throws exa::Error when it cannot) and, where the content is there,
  /// starts the render thread.
  void bind();
  /// The content of a server made without it (once; throws exa::Error for a second or an empty
  /// one); binds where bind() has not.
  void show(ViewContent content);
  int port() const;
  const std::string& token() const;
  /// The address to open, token included.
  std::string url() const;
  /// Serves until stop() (from any thread, e.g. a signal handler's thread).
  void run();
  void stop();

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace view
} // namespace exa
