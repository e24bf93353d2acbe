#include "server_impl.h"

#include <cstring>
#include <fstream>
#include <iterator>

namespace exa::view {

namespace {

/// A download's content type by the file's name.
const char* contentType(const std::string& name) {
  const auto ends = [&](const char* ext) {
    const size_t n = std::strlen(ext);
    return name.size() > n && name.compare(name.size() - n, n, ext) == 0;
  };
  return ends(".png") ? "image/png" : ends(".mp4") ? "video/mp4" : "application/octet-stream";
}

/// The routes every kind of background job has (movies, pictures): GET /api/KIND?id=ID its state,
/// POST /api/KIND/cancel {"id": ID}, and GET /api/KIND/file?id=ID the finished file as an
/// attachment. A job is found only by the id the server made. `maker` gives the jobs' owner when a
/// request comes (it is made after the routes).
template <typename Maker> void jobRoutes(httplib::Server& http, const std::string& kind, Maker maker) {
  const auto idOf = [kind](const httplib::Request& req, const std::string& what) {
    if (!req.has_param("id")) reject(400, strCat(what, ": parameter 'id' is missing"));
    return req.get_param_value("id");
  };
  http.Get("/api/" + kind, [maker, kind, idOf](const httplib::Request& req, httplib::Response& res) {
    const json j = maker().status(idOf(req, kind));
    if (j.is_null()) reject(404, strCat(kind, ": no ", kind, " has that id"));
    sendJson(res, j);
  });
  http.Post("/api/" + kind + "/cancel", [maker, kind](const httplib::Request& req, httplib::Response& res) {
    const json body = parseBody(req);
    if (!body.is_object() || !body.contains("id") || !body["id"].is_string())
      reject(400, strCat(kind, " cancel: the body must be an object with the ", kind, "'s \"id\""));
    const std::string id = body["id"].get<std::string>();
    if (!maker().cancel(id)) reject(404, strCat(kind, " cancel: no ", kind, " has that id"));
    sendJson(res, maker().status(id));
  });
  http.Get("/api/" + kind + "/file", [maker, kind, idOf](const httplib::Request& req, httplib::Response& res) {
    const std::string what = kind + " file";
    const std::string id = idOf(req, what);
    const json j = maker().status(id);
    if (j.is_null()) reject(404, strCat(what, ": no ", kind, " has that id"));
    const auto [path, name] = maker().file(id);
    if (path.empty()) reject(409, strCat(what, ": the ", kind, " is ", j["state"].get<std::string>(), ", not done"));
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) reject(500, strCat(what, ": cannot read the ", kind));
    res.set_header("Content-Disposition", strCat("attachment; filename=\"", name, "\""));
    res.set_header("Cache-Control", "no-store");
    res.set_content(std::move(bytes), contentType(name));
  });
}

} // namespace

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
    session->setParticleInput(step.input);
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
    session->setParticleInput(step.input);
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
  jobRoutes(http, "movie", [this]() -> MovieMaker& { return *movies; });
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
  jobRoutes(http, "picture", [this]() -> PictureMaker& { return *pictures; });
}

} // namespace exa::view
