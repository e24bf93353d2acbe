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

// The smallest depth over each block of the full-resolution depth that a draft pixel covers: the
// draft's rays end no farther than the nearest opaque geometry of their block.
std::vector<float> blockDepth(const float* depth, int width, int height, int dw, int dh) {
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

vtkStandardNewMacro(vtkExaBricksVolumeMapper);

vtkExaBricksVolumeMapper::vtkExaBricksVolumeMapper() {
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
  this->View.reset(); // it refers to the engine's renderer
  this->Engine = std::move(engine);
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

void vtkExaBricksVolumeMapper::Show(exa::paraview::Engine& e, const exa::SceneDocument& doc) {
  if (!this->View || &this->View->renderer() != e.renderer.get()) {
    this->View.reset();
    this->View = std::make_unique<exa::ProgressiveView>(*e.renderer, this->Options.device, kDraftPolicy);
    this->StillImagePasses = -1;
  }
  this->View->setDevice(this->Options.device);
  bool restarted = true;
  try {
    restarted = this->View->show(doc);
  } catch (const exa::DeviceFallbackError& error) {
    // The device asked for cannot draw this scene: the view shows it on the CPU.
    vtkErrorMacro("ExaBricks: " << error.what());
  }
  if (restarted) this->StillImagePasses = -1;
  this->DeviceInUse = exa::deviceName(e.renderer->device());
}

void vtkExaBricksVolumeMapper::RenderDraft(vtkOpenGLRenderWindow* window, double targetSeconds) {
  exa::ProgressiveView& view = *this->View;
  const exa::Frame& frame = view.shown().frame;
  exa::Frame draft = view.draftFrame();
  // The draft's rays end no farther than the nearest opaque depth of the pixels each covers.
  std::vector<float> coarse;
  draft.depthLimit = nullptr;
  if (frame.depthLimit) {
    coarse = blockDepth(frame.depthLimit, frame.width, frame.height, draft.width, draft.height);
    draft.depthLimit = coarse.data();
    draft.depthLimitPlanar = true;
  }
  const int divisor = view.draftDivisor();
  // The next draft's divisor follows the time the view allows a frame.
  if (!view.renderDraft(draft, this->DraftBuffer, exa::PassControl(), targetSeconds)) return;
  this->Draw(window, this->DraftBuffer.resolve(), true);
  this->ShownPasses = 0;
  this->ShownDraft = true;
  this->DraftDivisor = divisor;
}

void vtkExaBricksVolumeMapper::RenderStill(vtkOpenGLRenderWindow* window) {
  exa::ProgressiveView& view = *this->View;
  const exa::PassControl control;
  // Renders asked of the interactor come only where an event loop runs whenever the application
  // is idle: Qt's interactor (ParaView's GUI), or a generic one whose application serves its
  // timers (its CreateOneShotTimer fails otherwise, as in pvbatch). pvpython's X interactor has a
  // loop only inside Interact(): a script's still render there refines in one go.
  vtkRenderWindowInteractor* interactor = window->GetInteractor();
  const bool later = !this->CompleteStillRenders && interactor && interactor->GetInitialized() &&
                     interactor->GetEnabled() &&
                     (interactor->IsA("QVTKInteractor") || interactor->IsA("vtkGenericRenderWindowInteractor"));
  if (!view.complete()) {
    if (later) {
      // Passes for a moment, then the next render adds more: the view stays responsive.
      exa::Timer timer;
      do
        view.refine(control);
      while (!view.complete() && timer.seconds() < kStillPassSeconds);
    }
    // Without an event loop to ask for the next render (pvbatch, a server), finish here.
    if (!view.complete() && !(later && this->ScheduleRender(interactor))) view.refineTo(view.targetPasses(), control);
  }
  if (this->StillImagePasses != view.passes()) {
    view.buffer().resolve(this->StillImage);
    this->StillImagePasses = view.passes();
  }
  this->Draw(window, this->StillImage, false);
  this->ShownPasses = view.passes();
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
    const std::vector<float> depth = this->ViewDepth(camera, aspect, x0, y0, width, height);
    auto doc = std::make_unique<exa::SceneDocument>();
    doc->scene = scene;
    doc->hasCamera = true;
    exa::Frame& frame = doc->frame;
    frame.camera = exa::paraview::cameraOf(camera, aspect);
    frame.width = width;
    frame.height = height;
    frame.rate = this->Options.rate;
    frame.samplesPerPixel = this->Options.samplesPerPixel;
    frame.validate();
    // Rays end at the opaque geometry's depth (the view keeps a copy).
    if (!depth.empty()) {
      frame.depthLimit = depth.data();
      frame.depthLimitPlanar = true;
    }
    this->Show(e, *doc);
    frame.depthLimit = nullptr;
    this->Document = std::move(doc);
    if (interactive)
      this->RenderDraft(window, 1.0 / updateRate);
    else
      this->RenderStill(window);
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
