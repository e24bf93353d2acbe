// A volume mapper that renders the leaf cells of AMR data with exabricks into the render view:
// the camera, view size and transfer function are the view's and the volume property's, every
// ray ends at the depth of the opaque geometry drawn before it, and the image is blended over
// the view's (premultiplied alpha). The mapper shows what it renders to an exa::ProgressiveView:
// interactive renders (the render window asks for more than one frame per second) draw the view's
// draft at a fraction of the resolution, upscaled; still renders add the view's passes, which
// last while the camera, size, scene, device and depth stay the same, up to the samples per pixel
// asked for.
#pragma once

#include "vtkAbstractVolumeMapper.h"

#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/progressive.h"

#include "vtkWeakPointer.h"

#include <memory>
#include <string>
#include <vector>

class vtkCamera;
class vtkColorTransferFunction;
class vtkOpenGLQuadHelper;
class vtkOpenGLRenderWindow;
class vtkPiecewiseFunction;
class vtkRenderWindowInteractor;
class vtkTextureObject;

namespace exa::paraview {

/// What the mapper renders: a built model of one field and a renderer over it.
struct Engine {
  std::string field;
  std::unique_ptr<Model> model;
  std::unique_ptr<Renderer> renderer;
  double bounds[6] = {0, 0, 0, 0, 0, 0};
};

/// What the representation's properties ask of the renderer, besides the transfer function.
struct Settings {
  float rate = 1.f;                          ///< Frame::rate
  Shading shading = Shading::Smooth;         ///< the volume's lighting while Shade is on
  int aoRays = 0;                            ///< ambient occlusion rays per iso-surface hit
  std::vector<float> isoValues;              ///< iso-surfaces of the rendered array
  std::vector<ClipPlane> clipPlanes;         ///< each removes the half-space its normal points into
  int samplesPerPixel = 8;                   ///< the passes a still image accumulates
  std::string device = "auto";               ///< one of exa::deviceChoices() (exa::selectDevice)
  Integrator integrator = Integrator::March; ///< the ray marcher or the volume path tracer
  PathTracing pathTracing;                   ///< the path tracer's medium and lights
  friend bool operator==(const Settings&, const Settings&) = default;
};

/// The exabricks transfer function of ParaView's colour map and opacity function over the colour
/// map's range (sampled at `samples` values; log10 positions for a logarithmic map). ParaView's
/// opacity is per `unitDistance` world units, exabricks' per finest cell (`cellWidth`); colours
/// are taken as the intensities VTK blends.
TransferFunction transferFunctionOf(vtkColorTransferFunction* color, vtkPiecewiseFunction* opacity, double unitDistance,
                                    double cellWidth, int samples = 256);

/// The exabricks camera of a VTK camera for a viewport of the given aspect (width / height).
Camera cameraOf(vtkCamera* camera, double aspect);

/// ParaView shows 8-bit images: rays end at this opacity, where what is left behind can change a
/// pixel by half a step at most. So can what a part behind adds when several processes render
/// parts of the data and IceT composites them (a ray is ended per part there).
constexpr float kTerminationOpacity = 1.f - 0.5f / 255.f;

/// The scene of one field: its transfer function, the volume lit by `shading` when `shade` is
/// on, and iso-surfaces at the settings' values, each in the colour the colour map gives its
/// value (the renderer's default colours without a colour map).
Scene sceneOf(const std::string& field, const TransferFunction& tf, vtkColorTransferFunction* color, bool shade,
              const Settings& settings);

} // namespace exa::paraview

class vtkExaBricksVolumeMapper : public vtkAbstractVolumeMapper {
public:
  static vtkExaBricksVolumeMapper* New();
  vtkTypeMacro(vtkExaBricksVolumeMapper, vtkAbstractVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetEngine(std::shared_ptr<exa::paraview::Engine> engine);
  void SetSettings(const exa::paraview::Settings& settings);
  const exa::paraview::Settings& GetSettings() const { return this->Options; }
  /// Still renders add every missing pass at once (screenshots, and views without an event loop
  /// that could ask for the next render).
  void SetCompleteStillRenders(bool complete) { this->CompleteStillRenders = complete; }

  ///@{
  /// What the last render drew: the passes its image holds (0 for a draft), whether it was a
  /// draft and at what divisor of the resolution, and where the renderer runs ("cpu", "cuda").
  int GetRefinementPasses() const { return this->ShownPasses; }
  bool GetLastRenderWasDraft() const { return this->ShownDraft; }
  int GetDraftDivisor() const { return this->DraftDivisor; }
  const char* GetDeviceInUse() const { return this->DeviceInUse.c_str(); }
  /// The scene document the last render drew (its scene, camera and full-resolution frame) as
  /// exa::writeSceneJson writes it; "{}" before the first.
  std::string GetSceneDocument() const;
  ///@}

  void Render(vtkRenderer* ren, vtkVolume* vol) override;
  double* GetBounds() override;
  using vtkAbstractVolumeMapper::GetBounds;
  void ReleaseGraphicsResources(vtkWindow* window) override;

protected:
  vtkExaBricksVolumeMapper();
  ~vtkExaBricksVolumeMapper() override;

private:
  vtkExaBricksVolumeMapper(const vtkExaBricksVolumeMapper&) = delete;
  void operator=(const vtkExaBricksVolumeMapper&) = delete;

  /// The opaque depth of the viewport as exabricks' planar depth (row 0 at the top; +inf where
  /// nothing opaque was drawn); empty when the depth buffer cannot be read.
  std::vector<float> ViewDepth(vtkCamera* camera, double aspect, int x0, int y0, int width, int height);
  /// Shows `doc` to the engine's view (made for the engine on its first render), on the device
  /// the Device setting asks for.
  void Show(exa::paraview::Engine& engine, const exa::SceneDocument& doc);
  /// Draws the view's draft, its divisor adapted to `targetSeconds`.
  void RenderDraft(vtkOpenGLRenderWindow* window, double targetSeconds);
  /// Adds the view's passes (all, or some and then asks for another render) and draws them.
  void RenderStill(vtkOpenGLRenderWindow* window);
  void Draw(vtkOpenGLRenderWindow* window, const exa::Image& image, bool smooth);
  /// Asks the render window's interactor for another render soon (refinement), where it has an
  /// event loop; false where it cannot.
  bool ScheduleRender(vtkRenderWindowInteractor* interactor);
  void CancelScheduledRender();
  void OnTimer(vtkObject* caller, unsigned long event, void* data);

  std::shared_ptr<exa::paraview::Engine> Engine;
  exa::paraview::Settings Options;
  bool CompleteStillRenders = false;
  vtkTextureObject* Texture = nullptr;
  vtkOpenGLQuadHelper* Quad = nullptr;
  bool WarnedDepth = false;

  // The drafts and passes of the engine's renderer, on the device it runs on.
  std::unique_ptr<exa::ProgressiveView> View;
  exa::FrameBuffer DraftBuffer;
  exa::Image StillImage;     ///< the view's passes resolved
  int StillImagePasses = -1; ///< the passes StillImage holds (-1: none of the view's)
  std::string DeviceInUse = "cpu";

  // What the last render drew.
  std::unique_ptr<exa::SceneDocument> Document;
  int DraftDivisor = 4;
  int ShownPasses = 0;
  bool ShownDraft = false;

  // A render asked of the interactor while the still image is refined.
  vtkWeakPointer<vtkRenderWindowInteractor> TimerInteractor;
  unsigned long TimerObserver = 0;
  int TimerId = 0;
};
