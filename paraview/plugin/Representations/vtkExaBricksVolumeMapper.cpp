#include "vtkExaBricksVolumeMapper.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/workflows/progressive.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkImageData.h"
#include "vtkMath.h"
#include "vtkMatrix4x4.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkPiecewiseFunction.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkShaderProgram.h"
#include "vtkTextureObject.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtk_glew.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace exa::paraview {

TransferFunction transferFunctionOf(vtkColorTransferFunction* color, vtkPiecewiseFunction* opacity, double unitDistance,
                                    double cellWidth, int samples) {
  TransferFunction tf;
  double range[2] = {0.0, 1.0};
  if (color)
    color->GetRange(range);
  else if (opacity)
    opacity->GetRange(range);
  if (!(range[1] > range[0])) range[1] = range[0] + 1.0;
  const bool log = color && color->GetScale() == VTK_CTF_LOG10 && range[0] > 0.0;
  tf.valueRange = range1f{float(range[0]), float(range[1])};
  tf.logScale = log;
  tf.colorMap.name = "ParaView";
  const double exponent = unitDistance > 0.0 ? cellWidth / unitDistance : 1.0;
  for (int i = 0; i < samples; ++i) {
    const double t = double(i) / double(samples - 1);
    const double v = log ? std::pow(10.0, std::log10(range[0]) + t * (std::log10(range[1]) - std::log10(range[0])))
                         : range[0] + t * (range[1] - range[0]);
    double rgb[3] = {1.0, 1.0, 1.0};
    if (color) color->GetColor(v, rgb);
    tf.colorMap.positions.push_back(float(t));
    tf.colorMap.colors.push_back(vec3f(float(rgb[0]), float(rgb[1]), float(rgb[2])));
    const double a = std::clamp(opacity ? opacity->GetValue(v) : t, 0.0, 1.0);
    tf.opacity.push_back({float(t), float(1.0 - std::pow(1.0 - a, exponent))});
  }
  tf.opacityScale = 1.f;
  return tf;
}

Camera cameraOf(vtkCamera* camera, double aspect) {
  Camera c;
  const double* p = camera->GetPosition();
  const double* f = camera->GetFocalPoint();
  const double* u = camera->GetViewUp();
  c.position = vec3d(p[0], p[1], p[2]);
  c.lookAt = vec3d(f[0], f[1], f[2]);
  c.up = vec3d(u[0], u[1], u[2]);
  c.orthographic = camera->GetParallelProjection() != 0;
  c.orthoHeight = 2.0 * camera->GetParallelScale();
  double angle = camera->GetViewAngle();
  if (camera->GetUseHorizontalViewAngle() && aspect > 0.0)
    angle = 2.0 * std::atan(std::tan(0.5 * angle * M_PI / 180.0) / aspect) * 180.0 / M_PI;
  c.fovy = angle;
  return c;
}

Scene sceneOf(const std::string& field, const TransferFunction& tf, vtkColorTransferFunction* color, bool shade,
              const Settings& settings) {
  Scene scene = Scene::volumeOf(tf, field);
  scene.integration.terminationOpacity = kTerminationOpacity;
  scene.shading = shade ? settings.shading : Shading::None;
  scene.ao.rays = settings.aoRays;
  scene.integration.integrator = settings.integrator;
  scene.pathTracing = settings.pathTracing;
  scene.iso.values = settings.isoValues;
  scene.clip.planes = settings.clipPlanes;
  if (color)
    for (float v : settings.isoValues) {
      double rgb[3] = {1.0, 1.0, 1.0};
      color->GetColor(v, rgb);
      scene.iso.colors.push_back(vec3f(float(rgb[0]), float(rgb[1]), float(rgb[2])));
    }
  return scene;
}

} // namespace exa::paraview

namespace {

// Renders whose window asks for more frames per second than this are interactive (ParaView asks
// for 5 while the user drags, 0.002 for still renders; VTK's interactor for 15 and 0.0001).
constexpr double kInteractiveUpdateRate = 1.0;
// A still render that may ask for the next one adds passes for about this long.
constexpr double kStillPassSeconds = 0.15;
// Drafts as the library's progressive views make them (their budget is the view's frame time).
const exa::DraftPolicy kDraftPolicy;

bool sameCamera(const exa::Camera& a, const exa::Camera& b) {
  return a.position == b.position && a.lookAt == b.lookAt && a.up == b.up && a.fovy == b.fovy &&
         a.orthographic == b.orthographic && a.orthoHeight == b.orthoHeight;
}

// The smallest depth over each block of the full-resolution depth that a draft pixel covers: the
// draft's rays end no farther than the nearest opaque geometry of their block.
std::vector<float> blockDepth(const std::vector<float>& depth, int width, int height, int dw, int dh) {
  std::vector<float> out(size_t(dw) * size_t(dh), std::numeric_limits<float>::infinity());
  for (int y = 0; y < height; ++y) {
    const int by = std::min(dh - 1, int(int64_t(y) * dh / height));
    for (int x = 0; x < width; ++x) {
      const int bx = std::min(dw - 1, int(int64_t(x) * dw / width));
      float& d = out[size_t(by) * size_t(dw) + size_t(bx)];
      d = std::min(d, depth[size_t(y) * size_t(width) + size_t(x)]);
    }
  }
  return out;
}

// The image, premultiplied, laid over the viewport as it is.
const char* const kFragmentShader = R"(//VTK::System::Dec
in vec2 texCoord;
uniform sampler2D image;
//VTK::Output::Dec
void main() { gl_FragData[0] = texture(image, texCoord); }
)";

} // namespace

struct vtkExaBricksVolumeMapper::Accumulation {
  // What the passes were rendered for: any change starts over.
  const exa::paraview::Engine* engine = nullptr;
  exa::Scene scene;
  exa::Camera camera;
  int width = 0, height = 0, samplesPerPixel = 0;
  float rate = 0.f;
  exa::Device device = exa::Device::Cpu;
  std::vector<float> depth;
  bool valid = false;

  exa::FrameBuffer buffer;
  exa::Image image; ///< the buffer resolved
  uint32_t resolvedPasses = 0;

  bool matches(const exa::paraview::Engine* e, const exa::Scene& s, const exa::Frame& f, exa::Device d,
               const std::vector<float>& z) const {
    return valid && engine == e && sameCamera(camera, f.camera) && width == f.width && height == f.height &&
           samplesPerPixel == f.samplesPerPixel && rate == f.rate && device == d && depth == z && sameScene(scene, s);
  }
  static bool sameScene(const exa::Scene& a, const exa::Scene& b) {
    return a.layers == b.layers && a.iso == b.iso && a.shading == b.shading && a.ao.rays == b.ao.rays &&
           a.ao.length == b.ao.length && a.ao.volume == b.ao.volume && a.volume == b.volume && a.clip == b.clip &&
           a.integration == b.integration && a.pathTracing == b.pathTracing;
  }
};

vtkStandardNewMacro(vtkExaBricksVolumeMapper);

vtkExaBricksVolumeMapper::vtkExaBricksVolumeMapper() : Still(std::make_unique<Accumulation>()) {
  // The data comes with the engine, not through the pipeline; vtkVolume draws only mappers with
  // an input, so the mapper has an empty one.
  vtkNew<vtkImageData> placeholder;
  this->SetInputDataObject(placeholder);
}

vtkExaBricksVolumeMapper::~vtkExaBricksVolumeMapper() {
  this->CancelScheduledRender();
  if (this->TimerInteractor && this->TimerObserver) this->TimerInteractor->RemoveObserver(this->TimerObserver);
  delete this->Quad;
  if (this->Texture) this->Texture->Delete();
}

void vtkExaBricksVolumeMapper::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Field: " << (this->Engine ? this->Engine->field : std::string("(none)")) << "\n";
}

void vtkExaBricksVolumeMapper::SetEngine(std::shared_ptr<exa::paraview::Engine> engine) {
  this->Engine = std::move(engine);
  this->Still->valid = false;
  this->Modified();
}

void vtkExaBricksVolumeMapper::SetSettings(const exa::paraview::Settings& settings) {
  if (settings == this->Options) return;
  this->Options = settings;
  this->Modified();
}

std::string vtkExaBricksVolumeMapper::GetSceneDocument() const {
  return this->Document ? exa::writeSceneJson(*this->Document) : std::string("{}");
}

double* vtkExaBricksVolumeMapper::GetBounds() {
  if (this->Engine)
    std::copy(this->Engine->bounds, this->Engine->bounds + 6, this->Bounds);
  else
    vtkMath::UninitializeBounds(this->Bounds);
  return this->Bounds;
}

std::vector<float> vtkExaBricksVolumeMapper::ViewDepth(vtkCamera* camera, double aspect, int x0, int y0, int width,
                                                       int height) {
  std::vector<float> raw(size_t(width) * size_t(height));
  while (glGetError() != GL_NO_ERROR) {
  }
  glReadPixels(x0, y0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, raw.data());
  if (glGetError() != GL_NO_ERROR) {
    if (!this->WarnedDepth) vtkWarningMacro("ExaBricks cannot read the depth buffer: the volume ignores depth");
    this->WarnedDepth = true;
    return {};
  }
  vtkNew<vtkMatrix4x4> inverse;
  vtkMatrix4x4::Invert(camera->GetProjectionTransformMatrix(aspect, -1.0, 1.0), inverse);
  const double* m = inverse->GetData(); // row-major
  std::vector<float> depth(raw.size());
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const float d = raw[size_t(j) * size_t(width) + size_t(i)];
      float& out = depth[size_t(height - 1 - j) * size_t(width) + size_t(i)];
      if (!(d < 1.f)) {
        out = std::numeric_limits<float>::infinity();
        continue;
      }
      const double x = 2.0 * (i + 0.5) / width - 1.0, y = 2.0 * (j + 0.5) / height - 1.0, z = 2.0 * d - 1.0;
      const double ez = m[8] * x + m[9] * y + m[10] * z + m[11];
      const double ew = m[12] * x + m[13] * y + m[14] * z + m[15];
      out = float(std::max(0.0, -ez / ew));
    }
  return depth;
}

void vtkExaBricksVolumeMapper::Draw(vtkOpenGLRenderWindow* window, const exa::Image& image, bool smooth) {
  // OpenGL's rows start at the bottom.
  std::vector<float> rows(image.pixels.size() * 4);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const exa::vec4f& p = image.at(x, image.height - 1 - y);
      float* q = &rows[(size_t(y) * size_t(image.width) + size_t(x)) * 4];
      q[0] = p.x, q[1] = p.y, q[2] = p.z, q[3] = p.w;
    }
  if (!this->Texture) this->Texture = vtkTextureObject::New();
  this->Texture->SetContext(window);
  // A draft is smaller than the viewport: blend its pixels linearly as it is stretched over it.
  const int filter = smooth ? vtkTextureObject::Linear : vtkTextureObject::Nearest;
  this->Texture->SetMinificationFilter(filter);
  this->Texture->SetMagnificationFilter(filter);
  this->Texture->SetWrapS(vtkTextureObject::ClampToEdge);
  this->Texture->SetWrapT(vtkTextureObject::ClampToEdge);
  this->Texture->Create2DFromRaw(unsigned(image.width), unsigned(image.height), 4, VTK_FLOAT, rows.data());
  if (!this->Quad)
    this->Quad = new vtkOpenGLQuadHelper(window, nullptr, kFragmentShader, "");
  else
    window->GetShaderCache()->ReadyShaderProgram(this->Quad->Program);
  if (!this->Quad->Program || !this->Quad->Program->GetCompiled()) {
    vtkErrorMacro("ExaBricks: the compositing shader did not compile");
    return;
  }
  vtkOpenGLState* state = window->GetState();
  vtkOpenGLState::ScopedglEnableDisable blend(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendFunc(state);
  vtkOpenGLState::ScopedglDepthMask depthMask(state);
  state->vtkglEnable(GL_BLEND);
  state->vtkglDisable(GL_DEPTH_TEST);
  state->vtkglDepthMask(GL_FALSE);
  state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  this->Texture->Activate();
  this->Quad->Program->SetUniformi("image", this->Texture->GetTextureUnit());
  this->Quad->Render();
  this->Texture->Deactivate();
}

void vtkExaBricksVolumeMapper::UpdateRenderer(exa::paraview::Engine& e, const exa::Scene& scene) {
  exa::Renderer& renderer = *e.renderer;
  const std::string& choice = this->Options.device;
  exa::SceneUpdate update;
  try {
    update = renderer.setScene(scene);
  } catch (const exa::Error& error) {
    if (renderer.device() == exa::Device::Cpu) throw;
    // The GPU lacks what this scene needs: the CPU renders it (said once for an explicit choice).
    if (choice != "auto")
      vtkErrorMacro("ExaBricks: the GPU cannot render this scene (" << error.what() << "); rendering on the CPU");
    renderer.setDevice(exa::Device::Cpu);
    renderer.setScene(scene);
    this->DeviceAwaitsScene = true;
    this->DeviceInUse = exa::deviceName(renderer.device());
    return;
  }
  // Back on the CPU for an earlier scene: a new scene may suit the GPU again.
  const bool retry = this->DeviceAwaitsScene && (update.volume || update.iso || update.meshes);
  if (this->DeviceEngine == &e && this->DeviceChoice == choice && !retry) return;
  this->DeviceEngine = &e;
  this->DeviceChoice = choice;
  try {
    exa::selectDevice(renderer, choice);
  } catch (const exa::Error& error) {
    renderer.setDevice(exa::Device::Cpu);
    vtkErrorMacro("ExaBricks: Device '" << choice << "' cannot be used (" << error.what() << "); rendering on the CPU");
  }
  // On the CPU while a GPU could be used: the scene is why, and the next one is tried again.
  this->DeviceAwaitsScene =
      renderer.device() == exa::Device::Cpu && choice != "cpu" && exa::cudaStatus().problem.empty();
  this->DeviceInUse = exa::deviceName(renderer.device());
}

void vtkExaBricksVolumeMapper::RenderDraft(exa::paraview::Engine& e, vtkOpenGLRenderWindow* window,
                                           const exa::Frame& frame, const std::vector<float>& depth,
                                           double targetSeconds) {
  exa::Frame draft = frame.preview(this->DraftDivisor, frame.rate * kDraftPolicy.rateFactor);
  draft.samplesPerPixel = 1;
  draft.frameIndex = 0;
  std::vector<float> coarse;
  if (!depth.empty()) {
    coarse = draft.width == frame.width && draft.height == frame.height
                 ? depth
                 : blockDepth(depth, frame.width, frame.height, draft.width, draft.height);
    draft.depthLimit = coarse.data();
    draft.depthLimitPlanar = true;
  }
  exa::RenderStats stats;
  const exa::Image image = e.renderer->render(draft, &stats);
  this->Draw(window, image, true);
  this->ShownPasses = 0;
  this->ShownDraft = true;
  // The next draft's divisor: as many pixels as fit the time the view allows a frame, at the
  // time per pixel this one took.
  this->DraftDivisor =
      exa::nextDraftDivisor(this->DraftDivisor, frame.width, frame.height, double(draft.width) * double(draft.height),
                            stats.seconds, targetSeconds, kDraftPolicy.maxDivisor);
}

void vtkExaBricksVolumeMapper::RenderStill(exa::paraview::Engine& e, vtkOpenGLRenderWindow* window,
                                           const exa::Frame& frame, std::vector<float> depth) {
  Accumulation& a = *this->Still;
  const exa::Device device = e.renderer->device();
  if (!a.matches(&e, e.renderer->scene(), frame, device, depth)) {
    a.engine = &e;
    a.scene = e.renderer->scene();
    a.camera = frame.camera;
    a.width = frame.width;
    a.height = frame.height;
    a.samplesPerPixel = frame.samplesPerPixel;
    a.rate = frame.rate;
    a.device = device;
    a.depth = std::move(depth);
    a.buffer.resize(frame.width, frame.height);
    a.resolvedPasses = 0;
    a.valid = true;
  }
  exa::Frame f = frame;
  if (!a.depth.empty()) {
    f.depthLimit = a.depth.data();
    f.depthLimitPlanar = true;
  }
  const int target = frame.samplesPerPixel;
  // Renders asked of the interactor come only where an event loop runs whenever the application
  // is idle: Qt's interactor (ParaView's GUI), or a generic one whose application serves its
  // timers (its CreateOneShotTimer fails otherwise, as in pvbatch). pvpython's X interactor has a
  // loop only inside Interact(): a script's still render there refines in one go.
  vtkRenderWindowInteractor* interactor = window->GetInteractor();
  const bool later = !this->CompleteStillRenders && interactor && interactor->GetInitialized() &&
                     interactor->GetEnabled() &&
                     (interactor->IsA("QVTKInteractor") || interactor->IsA("vtkGenericRenderWindowInteractor"));
  a.valid = false; // until the passes are in
  if (int(a.buffer.passes()) < target) {
    if (later) {
      // Passes for a moment, then the next render adds more: the view stays responsive.
      exa::Timer timer;
      do {
        f.frameIndex = int(a.buffer.passes());
        e.renderer->renderPass(f, a.buffer);
      } while (int(a.buffer.passes()) < target && timer.seconds() < kStillPassSeconds);
    }
    // Without an event loop to ask for the next render (pvbatch, a server), finish here.
    if (int(a.buffer.passes()) < target && !(later && this->ScheduleRender(interactor)))
      e.renderer->renderPasses(f, a.buffer, target);
  }
  a.valid = true;
  if (a.resolvedPasses != a.buffer.passes() || a.image.width != frame.width || a.image.height != frame.height) {
    a.buffer.resolve(a.image);
    a.resolvedPasses = a.buffer.passes();
  }
  this->Draw(window, a.image, false);
  this->ShownPasses = int(a.buffer.passes());
  this->ShownDraft = false;
}

bool vtkExaBricksVolumeMapper::ScheduleRender(vtkRenderWindowInteractor* interactor) {
  if (!interactor) return false;
  if (this->TimerInteractor != interactor) {
    this->CancelScheduledRender();
    if (this->TimerInteractor && this->TimerObserver) this->TimerInteractor->RemoveObserver(this->TimerObserver);
    this->TimerInteractor = interactor;
    this->TimerObserver = interactor->AddObserver(vtkCommand::TimerEvent, this, &vtkExaBricksVolumeMapper::OnTimer);
  }
  if (!this->TimerId) this->TimerId = interactor->CreateOneShotTimer(1);
  return this->TimerId != 0;
}

void vtkExaBricksVolumeMapper::CancelScheduledRender() {
  if (this->TimerInteractor && this->TimerId) this->TimerInteractor->DestroyTimer(this->TimerId);
  this->TimerId = 0;
}

void vtkExaBricksVolumeMapper::OnTimer(vtkObject*, unsigned long, void* data) {
  if (!data || !this->TimerId || *static_cast<int*>(data) != this->TimerId) return;
  this->TimerId = 0;
  // The interactor's render goes through the view (ParaView's interactor helper turns it into a
  // still render of the view proxy), which lets the representations update as usual.
  if (this->TimerInteractor) this->TimerInteractor->Render();
}

void vtkExaBricksVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol) {
  if (!this->Engine || !this->Engine->renderer) return;
  auto* window = vtkOpenGLRenderWindow::SafeDownCast(ren->GetRenderWindow());
  if (!window) {
    vtkErrorMacro("ExaBricks draws into OpenGL render windows only");
    return;
  }
  int width = 0, height = 0, x0 = 0, y0 = 0;
  ren->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  if (width < 1 || height < 1) return;
  const double aspect = double(width) / double(height);
  vtkCamera* camera = ren->GetActiveCamera();
  const double updateRate = window->GetDesiredUpdateRate();
  const bool interactive = updateRate > kInteractiveUpdateRate;
  if (interactive) this->CancelScheduledRender();
  try {
    exa::paraview::Engine& e = *this->Engine;
    vtkVolumeProperty* property = vol->GetProperty();
    const exa::Model& model = *e.model;
    const exa::vec3d& s = model.world.scale; // opacity is per finest cell (averaged over the axes)
    const double cellWidth = double(e.renderer->dataset().referenceWidth) * (s.x + s.y + s.z) / 3.0;
    vtkColorTransferFunction* color = property->GetRGBTransferFunction(0);
    const exa::Scene scene =
        exa::paraview::sceneOf(e.field,
                               exa::paraview::transferFunctionOf(color, property->GetScalarOpacity(0),
                                                                 property->GetScalarOpacityUnitDistance(0), cellWidth),
                               color, property->GetShade(0) != 0, this->Options);
    this->UpdateRenderer(e, scene);
    std::vector<float> depth = this->ViewDepth(camera, aspect, x0, y0, width, height);
    exa::Frame frame;
    frame.camera = exa::paraview::cameraOf(camera, aspect);
    frame.width = width;
    frame.height = height;
    frame.rate = this->Options.rate;
    frame.samplesPerPixel = this->Options.samplesPerPixel;
    frame.validate();
    this->Document = std::make_unique<exa::SceneDocument>();
    this->Document->scene = scene;
    this->Document->frame = frame;
    this->Document->hasCamera = true;
    if (interactive)
      this->RenderDraft(e, window, frame, depth, 1.0 / updateRate);
    else
      this->RenderStill(e, window, frame, std::move(depth));
  } catch (const std::exception& error) {
    vtkErrorMacro(<< error.what());
  }
}

void vtkExaBricksVolumeMapper::ReleaseGraphicsResources(vtkWindow* window) {
  if (this->Texture) this->Texture->ReleaseGraphicsResources(window);
  if (this->Quad) this->Quad->ReleaseGraphicsResources(window);
  delete this->Quad;
  this->Quad = nullptr;
}
