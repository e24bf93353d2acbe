#include "vtkExaBricksRepresentation.h"

#include "amr_cells.h"
#include "parallel_parts.h"
#include "vtkExaBricksVolumeMapper.h"

#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/render/scene_vocabulary.h"

#include "vtkDataObject.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMath.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkOverlappingAMR.h"
#include "vtkPVRenderView.h"
#include "vtkPolyData.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <vector>

class vtkExaBricksRepresentation::vtkInternals {
public:
  vtkSmartPointer<vtkOverlappingAMR> Data; ///< the input as RequestData last took it
  unsigned long Generation = 0;            ///< counts the inputs taken that differ from the last
  vtkOverlappingAMR* Source = nullptr;     ///< the input last taken, and its modification time
  vtkMTimeType SourceTime = 0;
  double Bounds[6] = {0, 0, 0, 0, 0, 0};
  std::shared_ptr<exa::paraview::Engine> Engine;
  std::string BuiltField;
  unsigned long BuiltGeneration = 0;
  int Builds = 0;
  // Several processes: each renders one convex part of the data (parallel_parts.h).
  double PartBounds[6] = {0, 0, 0, 0, 0, 0}; ///< this process's part, clipped to the data
  std::string PartsJson = "[]";              ///< what every process holds
  vtkNew<vtkPolyData> Placeholder;           ///< the view's handle on the part's bounds
  // The sky gradient's properties, applied while it is on.
  bool SkyGradient = false;
  exa::vec3f Sky{1.f}, Ground{1.f};
  std::string SceneJson; ///< the scene document last asked for
};

namespace {
// The processes that render together (a render server's or pvbatch's), or null for one.
vtkMultiProcessController* renderingProcesses() {
  vtkMultiProcessController* c = vtkMultiProcessController::GetGlobalController();
  return c && c->GetNumberOfProcesses() > 1 ? c : nullptr;
}

constexpr int kMaxClipPlanes = 64;

// Whether the view is capturing a screenshot: vtkPVView keeps the flag for its subclasses, and a
// member pointer formed through a subclass reads it.
struct ScreenshotFlag : vtkPVView {
  static bool of(vtkPVView* view) { return view && (view->*&ScreenshotFlag::GetInCaptureScreenshot)(); }
};
} // namespace

vtkStandardNewMacro(vtkExaBricksRepresentation);

vtkExaBricksRepresentation::vtkExaBricksRepresentation()
    : Internals(new vtkInternals), Actor(vtkVolume::New()), Mapper(vtkExaBricksVolumeMapper::New()) {
  this->Actor->SetMapper(this->Mapper);
  vtkMath::UninitializeBounds(this->Internals->Bounds);
}

vtkExaBricksRepresentation::~vtkExaBricksRepresentation() {
  this->Actor->Delete();
  this->Mapper->Delete();
  delete this->Internals;
}

void vtkExaBricksRepresentation::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  const exa::paraview::Settings& s = this->Mapper->GetSettings();
  os << indent << "Field: " << this->Internals->BuiltField << "\n";
  os << indent << "Model builds: " << this->Internals->Builds << "\n";
  os << indent << "Sampling rate: " << s.rate << "\n";
  os << indent << "Shading: " << exa::nameOf(s.shading) << "\n";
  os << indent << "Integrator: " << exa::nameOf(s.integrator) << "\n";
  os << indent << "Ambient occlusion rays: " << s.aoRays << "\n";
  os << indent << "Iso values: " << s.isoValues.size() << "\n";
  os << indent << "Samples per pixel: " << s.samplesPerPixel << "\n";
  os << indent << "Device: " << s.device << " (in use: " << this->Mapper->GetDeviceInUse() << ")\n";
}

int vtkExaBricksRepresentation::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkOverlappingAMR");
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

int vtkExaBricksRepresentation::RequestData(vtkInformation* request, vtkInformationVector** inputs,
                                            vtkInformationVector* outputs) {
  vtkInternals& in = *this->Internals;
  vtkOverlappingAMR* amr =
      inputs[0]->GetNumberOfInformationObjects() == 1 ? vtkOverlappingAMR::GetData(inputs[0], 0) : nullptr;
  // The representation re-executes for reasons other than new data (a representation switch,
  // for one): the model is rebuilt only for an input that is another one or was modified.
  if (!amr || amr != in.Source || amr->GetMTime() != in.SourceTime || !in.Data) {
    vtkMath::UninitializeBounds(in.Bounds);
    in.Data = nullptr;
    if (amr) {
      in.Data = vtkSmartPointer<vtkOverlappingAMR>::New();
      in.Data->ShallowCopy(amr);
      amr->GetBounds(in.Bounds);
    }
    in.Source = amr;
    in.SourceTime = amr ? amr->GetMTime() : 0;
    ++in.Generation;
  }
  return this->Superclass::RequestData(request, inputs, outputs);
}

int vtkExaBricksRepresentation::ProcessViewRequest(vtkInformationRequestKey* request, vtkInformation* inInfo,
                                                   vtkInformation* outInfo) {
  if (!this->Superclass::ProcessViewRequest(request, inInfo, outInfo)) return 0;
  vtkInternals& in = *this->Internals;
  if (request == vtkPVView::REQUEST_UPDATE()) {
    // The cells stay where they were read: render there.
    vtkPVRenderView::SetRequiresDistributedRendering(inInfo, this, true);
    if (renderingProcesses()) {
      // Every process builds its convex part (a collective, so here, where every process comes
      // at once) and tells the view the part's bounds: IceT composites the processes' images in
      // the visibility order of these boxes, and other data is redistributed to match.
      this->UpdateEngine();
      vtkPVView::SetPiece(inInfo, this, in.Placeholder);
      vtkPVRenderView::SetGeometryBounds(inInfo, this, in.PartBounds);
      vtkPVRenderView::SetOrderedCompositingConfiguration(inInfo, this, vtkPVRenderView::USE_BOUNDS_FOR_REDISTRIBUTION,
                                                          in.PartBounds);
      outInfo->Set(vtkPVRenderView::NEED_ORDERED_COMPOSITING(), 1);
    } else {
      vtkPVRenderView::SetGeometryBounds(inInfo, this, in.Bounds);
    }
  } else if (request == vtkPVView::REQUEST_RENDER()) {
    if (!renderingProcesses()) this->UpdateEngine();
    // A screenshot takes the refined image at once.
    this->Mapper->SetCompleteStillRenders(ScreenshotFlag::of(vtkPVView::SafeDownCast(this->GetView())));
  }
  return 1;
}

void vtkExaBricksRepresentation::UpdateEngine() {
  vtkInternals& in = *this->Internals;
  vtkInformation* info = this->GetInputArrayInformation(0);
  const char* name = info && info->Has(vtkDataObject::FIELD_NAME()) ? info->Get(vtkDataObject::FIELD_NAME()) : nullptr;
  vtkMultiProcessController* processes = renderingProcesses();
  bool rebuild = !in.Engine || !name || in.BuiltField != name || in.BuiltGeneration != in.Generation;
  bool drop = !in.Data || !name || !*name;
  if (processes) {
    // The processes decide together: a build is a collective.
    int mine[2] = {rebuild ? 1 : 0, drop ? 1 : 0}, any[2] = {0, 0};
    processes->AllReduce(mine, any, 2, vtkCommunicator::MAX_OP);
    rebuild = any[0] != 0;
    drop = any[1] != 0;
  }
  if (drop) {
    in.Engine.reset();
    this->Mapper->SetEngine(nullptr);
    return;
  }
  if (!rebuild) return;
  in.Engine.reset();
  this->Mapper->SetEngine(nullptr);
  in.BuiltField = name;
  in.BuiltGeneration = in.Generation;
  if (info->Has(vtkDataObject::FIELD_ASSOCIATION()) &&
      info->Get(vtkDataObject::FIELD_ASSOCIATION()) != vtkDataObject::FIELD_ASSOCIATION_CELLS) {
    vtkErrorMacro("ExaBricks renders cell arrays; '" << name << "' is not one");
    return;
  }
  try {
    ++in.Builds;
    auto engine = std::make_shared<exa::paraview::Engine>();
    engine->field = name;
    if (processes) {
      exa::paraview::ControllerCollectives comm(processes);
      exa::paraview::ProcessPart part = exa::paraview::buildProcessPart(in.Data, name, comm);
      engine->model = std::move(part.model);
      if (engine->model) {
        engine->renderer = std::make_unique<exa::Renderer>(*engine->model, part.dataset);
        engine->renderer->setDomain(part.domain);
      }
      if (!std::equal(part.bounds, part.bounds + 6, in.PartBounds)) {
        std::copy(part.bounds, part.bounds + 6, in.PartBounds);
        // The view builds its cuts anew only when the data it was handed changed.
        in.Placeholder->Modified();
      }
      std::copy(part.bounds, part.bounds + 6, engine->bounds);
      in.PartsJson = part.partsJson;
    } else {
      engine->model = std::make_unique<exa::Model>(exa::paraview::amrModel(in.Data, name));
      engine->renderer = std::make_unique<exa::Renderer>(*engine->model);
      std::copy(in.Bounds, in.Bounds + 6, engine->bounds);
      const exa::paraview::PartNumbers whole = exa::paraview::partNumbers(engine->model.get(), 0);
      in.PartsJson = exa::paraview::partsJson({{whole.cells, whole.cells, whole.bytes}});
    }
    in.Engine = engine;
    this->Mapper->SetEngine(engine);
  } catch (const std::exception& error) {
    vtkErrorMacro(<< error.what());
  }
}

void vtkExaBricksRepresentation::SetVisibility(bool visible) {
  this->Superclass::SetVisibility(visible);
  this->Actor->SetVisibility(visible);
}

void vtkExaBricksRepresentation::SetColor(vtkColorTransferFunction* color) {
  this->Actor->GetProperty()->SetColor(color);
}

void vtkExaBricksRepresentation::SetScalarOpacity(vtkPiecewiseFunction* opacity) {
  this->Actor->GetProperty()->SetScalarOpacity(opacity);
}

void vtkExaBricksRepresentation::SetScalarOpacityUnitDistance(double distance) {
  this->Actor->GetProperty()->SetScalarOpacityUnitDistance(distance);
}

void vtkExaBricksRepresentation::SetShade(bool shade) { this->Actor->GetProperty()->SetShade(shade); }

void vtkExaBricksRepresentation::SetSamplingRate(double rate) {
  if (!(rate > 0.0 && rate <= 1024.0)) {
    vtkErrorMacro("ExaBricks: Sampling Rate must be above 0 and at most 1024, not " << rate);
    return;
  }
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.rate = float(rate);
  this->Mapper->SetSettings(s);
}

double vtkExaBricksRepresentation::GetSamplingRate() { return this->Mapper->GetSettings().rate; }

void vtkExaBricksRepresentation::SetAmbientOcclusionRays(int rays) {
  if (rays < 0 || rays > 1024) {
    vtkErrorMacro("ExaBricks: Ambient Occlusion Rays must be 0 (off) to 1024, not " << rays);
    return;
  }
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.aoRays = rays;
  this->Mapper->SetSettings(s);
}

int vtkExaBricksRepresentation::GetAmbientOcclusionRays() { return this->Mapper->GetSettings().aoRays; }

namespace {

/// Whether a value is valid for a scene setting; otherwise the library's message (which names
/// the key, as every front end says it).
bool validSetting(vtkObject* self, const char* key, double value) {
  try {
    exa::checkSceneSetting(key, value);
    return true;
  } catch (const exa::Error& e) {
    vtkErrorWithObjectMacro(self, "ExaBricks: " << e.what());
    return false;
  }
}

/// The value a choice's name stands for, as the library names it; false (and the library's
/// message) for another name.
template <typename E> bool parseChoice(vtkObject* self, const char* what, const char* name, E& value) {
  try {
    value = exa::parseName<E>(name ? name : "", what);
    return true;
  } catch (const exa::Error& e) {
    vtkErrorWithObjectMacro(self, "ExaBricks: " << e.what());
    return false;
  }
}

/// A choice as state files saved it: by name, or (files saved while the choices were numbered
/// enumerations) by its index in the enumeration of then, `earlier`.
const char* savedChoice(const char* value, std::initializer_list<const char*> earlier) {
  if (value && value[0] >= '0' && value[0] <= '9' && value[1] == '\0' && size_t(value[0] - '0') < earlier.size())
    return earlier.begin()[value[0] - '0'];
  return value;
}

/// A vector setting checked against the scene vocabulary's kind; false (and an error) when refused.
bool validVector(vtkObject* self, const char* key, const exa::vec3f& value) {
  try {
    exa::checkSceneVector(key, value);
    return true;
  } catch (const exa::Error& e) {
    vtkErrorWithObjectMacro(self, "ExaBricks: " << e.what());
    return false;
  }
}

/// Sets a number of the path tracer after checking it against the scene vocabulary.
void setPathNumber(vtkObject* self, vtkExaBricksVolumeMapper* mapper, const char* key, double value,
                   float exa::PathTracing::*member) {
  if (!validSetting(self, key, value)) return;
  exa::paraview::Settings s = mapper->GetSettings();
  s.pathTracing.*member = float(value);
  mapper->SetSettings(s);
}

} // namespace

void vtkExaBricksRepresentation::SetShading(const char* shading) {
  exa::Shading value;
  if (!parseChoice(this, "Shading", savedChoice(shading, {"smooth", "analytic", "central", "none"}), value)) return;
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.shading = value;
  this->Mapper->SetSettings(s);
}

const char* vtkExaBricksRepresentation::GetShading() { return exa::nameOf(this->Mapper->GetSettings().shading); }

void vtkExaBricksRepresentation::SetIntegrator(const char* integrator) {
  exa::Integrator value;
  if (!parseChoice(this, "Integrator", savedChoice(integrator, {"march", "pathtrace"}), value)) return;
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.integrator = value;
  this->Mapper->SetSettings(s);
}

const char* vtkExaBricksRepresentation::GetIntegrator() { return exa::nameOf(this->Mapper->GetSettings().integrator); }

void vtkExaBricksRepresentation::SetAlbedo(double v) {
  setPathNumber(this, this->Mapper, "pathtrace.albedo", v, &exa::PathTracing::albedo);
}
void vtkExaBricksRepresentation::SetAnisotropy(double v) {
  setPathNumber(this, this->Mapper, "pathtrace.anisotropy", v, &exa::PathTracing::anisotropy);
}
void vtkExaBricksRepresentation::SetEmission(double v) {
  setPathNumber(this, this->Mapper, "pathtrace.emission", v, &exa::PathTracing::emission);
}
void vtkExaBricksRepresentation::SetSunIntensity(double v) {
  setPathNumber(this, this->Mapper, "pathtrace.sun_intensity", v, &exa::PathTracing::sunIntensity);
}
void vtkExaBricksRepresentation::SetSunAngle(double v) {
  setPathNumber(this, this->Mapper, "pathtrace.sun_angle", v, &exa::PathTracing::sunAngle);
}

void vtkExaBricksRepresentation::SetBounces(int bounces) {
  if (!validSetting(this, "pathtrace.bounces", bounces)) return;
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.pathTracing.bounces = bounces;
  this->Mapper->SetSettings(s);
}

void vtkExaBricksRepresentation::SetEnvironment(double r, double g, double b) {
  const exa::vec3f v{float(r), float(g), float(b)};
  if (!validVector(this, "pathtrace.environment", v)) return;
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.pathTracing.environment = v;
  this->Mapper->SetSettings(s);
}

void vtkExaBricksRepresentation::ApplySky() {
  const vtkInternals& in = *this->Internals;
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.pathTracing.sky = in.SkyGradient ? std::optional<exa::vec3f>(in.Sky) : std::nullopt;
  s.pathTracing.ground = in.SkyGradient ? std::optional<exa::vec3f>(in.Ground) : std::nullopt;
  this->Mapper->SetSettings(s);
}

void vtkExaBricksRepresentation::SetSkyGradient(int on) {
  this->Internals->SkyGradient = on != 0;
  this->ApplySky();
}

void vtkExaBricksRepresentation::SetSky(double r, double g, double b) {
  const exa::vec3f v{float(r), float(g), float(b)};
  if (!validVector(this, "pathtrace.sky", v)) return;
  this->Internals->Sky = v;
  this->ApplySky();
}

void vtkExaBricksRepresentation::SetGround(double r, double g, double b) {
  const exa::vec3f v{float(r), float(g), float(b)};
  if (!validVector(this, "pathtrace.ground", v)) return;
  this->Internals->Ground = v;
  this->ApplySky();
}

void vtkExaBricksRepresentation::SetSunDirection(double x, double y, double z) {
  const exa::vec3f v{float(x), float(y), float(z)};
  if (!validVector(this, "pathtrace.sun_direction", v)) return;
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.pathTracing.sunDirection = v;
  this->Mapper->SetSettings(s);
}

void vtkExaBricksRepresentation::SetNumberOfIsoValues(int count) {
  if (count < 0) {
    vtkErrorMacro("ExaBricks: the number of Iso Values cannot be negative (" << count << ")");
    return;
  }
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.isoValues.resize(size_t(count), 0.f);
  this->Mapper->SetSettings(s);
}

void vtkExaBricksRepresentation::SetIsoValue(int index, double value) {
  if (index < 0 || !std::isfinite(value)) {
    vtkErrorMacro("ExaBricks: Iso Values must be finite numbers, not " << value << " (value " << index << ")");
    return;
  }
  exa::paraview::Settings s = this->Mapper->GetSettings();
  if (size_t(index) >= s.isoValues.size()) s.isoValues.resize(size_t(index) + 1, 0.f);
  s.isoValues[size_t(index)] = float(value);
  this->Mapper->SetSettings(s);
}

int vtkExaBricksRepresentation::GetNumberOfIsoValues() { return int(this->Mapper->GetSettings().isoValues.size()); }

double vtkExaBricksRepresentation::GetIsoValue(int index) {
  const std::vector<float>& v = this->Mapper->GetSettings().isoValues;
  return index >= 0 && size_t(index) < v.size() ? v[size_t(index)] : 0.0;
}

void vtkExaBricksRepresentation::SetNumberOfClipPlanes(int count) {
  if (count < 0 || count > kMaxClipPlanes) {
    vtkErrorMacro("ExaBricks: 0 to " << kMaxClipPlanes << " Clip Planes, not " << count);
    return;
  }
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.clipPlanes.resize(size_t(count));
  this->Mapper->SetSettings(s);
}

void vtkExaBricksRepresentation::SetClipPlane(int index, double ox, double oy, double oz, double nx, double ny,
                                              double nz) {
  const double values[6] = {ox, oy, oz, nx, ny, nz};
  const bool finite = std::all_of(values, values + 6, [](double v) { return std::isfinite(v); });
  if (index < 0 || index >= kMaxClipPlanes || !finite || (nx == 0.0 && ny == 0.0 && nz == 0.0)) {
    vtkErrorMacro("ExaBricks: a Clip Plane is a point and a normal that is not zero, all finite (plane " << index
                                                                                                         << ")");
    return;
  }
  exa::paraview::Settings s = this->Mapper->GetSettings();
  if (size_t(index) >= s.clipPlanes.size()) s.clipPlanes.resize(size_t(index) + 1);
  s.clipPlanes[size_t(index)] = exa::ClipPlane{exa::vec3d(ox, oy, oz), exa::normalize(exa::vec3d(nx, ny, nz))};
  this->Mapper->SetSettings(s);
}

int vtkExaBricksRepresentation::GetNumberOfClipPlanes() { return int(this->Mapper->GetSettings().clipPlanes.size()); }

void vtkExaBricksRepresentation::SetSamplesPerPixel(int samples) {
  if (samples < 1 || samples > 65536) {
    vtkErrorMacro("ExaBricks: Samples Per Pixel must be 1 to 65536, not " << samples);
    return;
  }
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.samplesPerPixel = samples;
  this->Mapper->SetSettings(s);
}

int vtkExaBricksRepresentation::GetSamplesPerPixel() { return this->Mapper->GetSettings().samplesPerPixel; }

void vtkExaBricksRepresentation::SetDevice(const char* device) {
  device = savedChoice(device, {"auto", "cpu", "cuda"});
  const std::vector<std::string>& choices = exa::deviceChoices();
  if (!device || std::find(choices.begin(), choices.end(), device) == choices.end()) {
    std::string names;
    for (const std::string& c : choices)
      names += (names.empty() ? "" : ", ") + c;
    vtkErrorMacro("ExaBricks: Device is '" << (device ? device : "") << "' (choose from: " << names << ")");
    return;
  }
  exa::paraview::Settings s = this->Mapper->GetSettings();
  s.device = device;
  this->Mapper->SetSettings(s);
}

const char* vtkExaBricksRepresentation::GetDevice() { return this->Mapper->GetSettings().device.c_str(); }

const char* vtkExaBricksRepresentation::GetSceneDocument() {
  this->Internals->SceneJson = this->Mapper->GetSceneDocument();
  return this->Internals->SceneJson.c_str();
}

int vtkExaBricksRepresentation::GetModelBuilds() { return this->Internals->Builds; }

const char* vtkExaBricksRepresentation::GetPartsInformation() { return this->Internals->PartsJson.c_str(); }

int vtkExaBricksRepresentation::GetRefinementPasses() { return this->Mapper->GetRefinementPasses(); }

const char* vtkExaBricksRepresentation::GetDeviceInUse() { return this->Mapper->GetDeviceInUse(); }

bool vtkExaBricksRepresentation::AddToView(vtkView* view) {
  vtkPVRenderView* renderView = vtkPVRenderView::SafeDownCast(view);
  if (!renderView) return false;
  renderView->GetRenderer()->AddActor(this->Actor);
  return this->Superclass::AddToView(view);
}

bool vtkExaBricksRepresentation::RemoveFromView(vtkView* view) {
  vtkPVRenderView* renderView = vtkPVRenderView::SafeDownCast(view);
  if (!renderView) return false;
  renderView->GetRenderer()->RemoveActor(this->Actor);
  return this->Superclass::RemoveFromView(view);
}
