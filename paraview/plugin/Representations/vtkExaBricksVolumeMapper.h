// A volume mapper that renders the leaf cells of AMR data with exabricks into the render view:
// the camera, view size and transfer function are the view's and the volume property's, every
// ray ends at the depth of the opaque geometry drawn before it, and the image is blended over
// the view's (premultiplied alpha).
#pragma once

#include "vtkAbstractVolumeMapper.h"

#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"

#include <memory>
#include <string>
#include <vector>

class vtkCamera;
class vtkColorTransferFunction;
class vtkOpenGLQuadHelper;
class vtkOpenGLRenderWindow;
class vtkPiecewiseFunction;
class vtkTextureObject;

namespace exa::paraview {

/// What the mapper renders: a built model of one field and a renderer over it.
struct Engine {
  std::string field;
  std::unique_ptr<Model> model;
  std::unique_ptr<Renderer> renderer;
  double bounds[6] = {0, 0, 0, 0, 0, 0};
};

/// The exabricks transfer function of ParaView's colour map and opacity function over the colour
/// map's range (sampled at `samples` values; log10 positions for a logarithmic map). ParaView's
/// opacity is per `unitDistance` world units, exabricks' per finest cell (`cellWidth`); colours
/// are taken as the intensities VTK blends.
TransferFunction transferFunctionOf(vtkColorTransferFunction* color, vtkPiecewiseFunction* opacity, double unitDistance,
                                    double cellWidth, int samples = 256);

/// The exabricks camera of a VTK camera for a viewport of the given aspect (width / height).
Camera cameraOf(vtkCamera* camera, double aspect);

} // namespace exa::paraview

class vtkExaBricksVolumeMapper : public vtkAbstractVolumeMapper {
public:
  static vtkExaBricksVolumeMapper* New();
  vtkTypeMacro(vtkExaBricksVolumeMapper, vtkAbstractVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetEngine(std::shared_ptr<exa::paraview::Engine> engine);

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
  void Draw(vtkOpenGLRenderWindow* window, const exa::Image& image);

  std::shared_ptr<exa::paraview::Engine> Engine;
  vtkTextureObject* Texture = nullptr;
  vtkOpenGLQuadHelper* Quad = nullptr;
  bool WarnedDepth = false;
};
