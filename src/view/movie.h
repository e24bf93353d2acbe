// Movies made by the viewer: the series (one frame per step) or an orbit of the one step, with
// the scene on screen, rendered on a background thread into a folder of the server's own and
// encoded with ffmpeg. A movie is known by the id made here; its file is only ever served by that
// id. One movie renders at a time; it can be cancelled between frames.
#pragma once

#include "exabricks/render/scene.h"
#include "exabricks/workflows/series.h"
#include "jobs.h"
#include "steps.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace exa::view {

struct MovieInput {
  SceneDocument doc;
  std::vector<std::string> steps; ///< more than one: a frame per step
  SeriesOptions series;           ///< how the steps load (and the march's options)
  StepView current;               ///< the dataset an orbit shows
  int orbitFrames = 48;           ///< frames of an orbit (a single step)
  double fps = 24;
};

class MovieMaker {
public:
  MovieMaker();
  ~MovieMaker(); ///< cancels a movie in progress and removes the movies' folder
  MovieMaker(const MovieMaker&) = delete;
  MovieMaker& operator=(const MovieMaker&) = delete;

  /// Whether ffmpeg is installed (the movies need it).
  static bool canEncode();
  /// Whether a movie is rendering or encoding now.
  bool busy() const;
  /// Starts a movie; returns its id. Throws exa::Error when another one is in progress or there is
  /// no ffmpeg.
  std::string start(MovieInput input);
  /// The movie's state (null for an unknown id): state, frames, done, error.
  nlohmann::json status(const std::string& id) const;
  /// Asks the movie to stop after the frame in progress; false for an unknown id.
  bool cancel(const std::string& id);
  /// The finished movie's file and its name in a download, or empty (unknown id, or not finished).
  std::pair<std::string, std::string> file(const std::string& id) const;

private:
  struct MovieJob;
  void run(MovieJob& job, const MovieInput& input);

  std::string folder_; ///< holds one subfolder per movie
  JobTable<MovieJob> jobs_;
};

} // namespace exa::view
