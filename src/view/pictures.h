// Pictures saved by the viewer at publication size: the scene on screen rendered on a background
// thread at a chosen size and samples per pixel, with progress and cancel between tiles, written as
// PNG (8 or 16 bits), OpenEXR or PFM into a folder of the server's own. A picture is known by the id
// made here and served only by that id, under a name made of the dataset, field and size.
#pragma once

#include "exabricks/documents/image.h"
#include "exabricks/render/legends.h"
#include "exabricks/render/renderer.h"
#include "jobs.h"
#include "steps.h"

#include <nlohmann/json.hpp>

#include <memory>
#include <string>

namespace exa::view {

struct PictureInput {
  SceneDocument doc; ///< its frame has the picture's size and samples per pixel
  StepView step;     ///< the dataset shown
  LegendText legends;
  RendererOptions renderer;
  ImageFormat format = ImageFormat::Png;
  std::string name; ///< the file's name (the dataset, field and size, and the format's extension)
};

class PictureMaker {
public:
  PictureMaker();
  ~PictureMaker(); ///< cancels a picture in progress and removes the pictures' folder
  PictureMaker(const PictureMaker&) = delete;
  PictureMaker& operator=(const PictureMaker&) = delete;

  bool busy() const;
  /// Starts a picture; returns its id. Throws exa::Error when another one is in progress.
  std::string start(PictureInput input);
  /// The picture's state (null for an unknown id): state, passes, done tiles of all, error, name.
  nlohmann::json status(const std::string& id) const;
  /// Asks the picture to stop before its next tile; false for an unknown id.
  bool cancel(const std::string& id);
  /// The finished picture's file and name, or an empty path (unknown id, or not finished).
  std::pair<std::string, std::string> file(const std::string& id) const;

private:
  struct PictureJob;
  void run(PictureJob& job, const PictureInput& input);

  std::string folder_;
  JobTable<PictureJob> jobs_;
};

/// A file name of the dataset, field and size, with the format's extension
/// ("plt00100-density-4096x4096.png"); only letters, digits, '.', '-' and '_'.
std::string pictureName(const std::string& dataset, const std::string& field, int width, int height,
                        ImageFormat format);

} // namespace exa::view
