#include "server_impl.h"

#include <fstream>
#include <iterator>

namespace exa::view {

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

} // namespace exa::view
