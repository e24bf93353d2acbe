/**
 * @class vtkExaBricksRepresentation
 * @brief Overlapping AMR data rendered by exabricks in a render view.
 *
 * The leaf cells of the chosen cell array (every block's cells less those a finer block
 * covers) become an exabricks model, built once per input and array. It is drawn as a volume
 * with the view's camera and size, the colour map and opacity function of the representation,
 * and the opaque geometry's depth: each ray ends where that geometry begins.
 */
#pragma once

#include "vtkPVDataRepresentation.h"

#include "ExaBricksRepresentationsModule.h" // for export macro

class vtkColorTransferFunction;
class vtkExaBricksVolumeMapper;
class vtkOverlappingAMR;
class vtkPiecewiseFunction;
class vtkVolume;

class EXABRICKSREPRESENTATIONS_EXPORT vtkExaBricksRepresentation : public vtkPVDataRepresentation {
public:
  static vtkExaBricksRepresentation* New();
  vtkTypeMacro(vtkExaBricksRepresentation, vtkPVDataRepresentation);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  int ProcessViewRequest(vtkInformationRequestKey* request, vtkInformation* inInfo, vtkInformation* outInfo) override;
  void SetVisibility(bool visible) override;

  ///@{
  /// The colour map, opacity function (per ScalarOpacityUnitDistance world units) and lighting.
  void SetColor(vtkColorTransferFunction* color);
  void SetScalarOpacity(vtkPiecewiseFunction* opacity);
  void SetScalarOpacityUnitDistance(double distance);
  void SetShade(bool shade);
  ///@}

protected:
  vtkExaBricksRepresentation();
  ~vtkExaBricksRepresentation() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputs, vtkInformationVector* outputs) override;
  bool AddToView(vtkView* view) override;
  bool RemoveFromView(vtkView* view) override;

private:
  vtkExaBricksRepresentation(const vtkExaBricksRepresentation&) = delete;
  void operator=(const vtkExaBricksRepresentation&) = delete;

  /// Builds the model of the chosen array when the input or the array changed.
  void UpdateEngine();

  class vtkInternals;
  vtkInternals* Internals;
  vtkVolume* Actor;
  vtkExaBricksVolumeMapper* Mapper;
};
