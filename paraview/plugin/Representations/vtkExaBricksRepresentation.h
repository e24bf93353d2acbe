/**
 * @class vtkExaBricksRepresentation
 * @brief Overlapping AMR data rendered by exabricks in a render view.
 *
 * The leaf cells of the chosen cell array (every block's cells less those a finer block
 * covers) become an exabricks model, built once per input and array. It is drawn as a volume
 * with the view's camera and size, the colour map and opacity function of the representation,
 * and the opaque geometry's depth: each ray ends where that geometry begins. The renderer's
 * settings (sampling rate, shading, ambient occlusion, iso-values, samples per pixel, device)
 * change the scene or the frame, never the model: interactive renders draw a draft, still
 * renders refine up to the samples per pixel.
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

  ///@{
  /// The renderer's settings. Invalid values are refused with an error and leave the setting as
  /// it was.
  void SetSamplingRate(double rate);
  double GetSamplingRate();
  /// How the volume is lit while Shade is on, named as scene files name it (scene key shading).
  void SetShading(const char* shading);
  const char* GetShading();
  void SetAmbientOcclusionRays(int rays);
  int GetAmbientOcclusionRays();
  void SetNumberOfIsoValues(int count);
  void SetIsoValue(int index, double value);
  int GetNumberOfIsoValues();
  double GetIsoValue(int index);
  /// Clip planes: each removes the half-space its normal points into (world coordinates), from
  /// the volume and the iso-surfaces.
  void SetNumberOfClipPlanes(int count);
  void SetClipPlane(int index, double ox, double oy, double oz, double nx, double ny, double nz);
  int GetNumberOfClipPlanes();
  void SetSamplesPerPixel(int samples);
  int GetSamplesPerPixel();
  /// One of exa::deviceChoices(): auto (the GPU where one can be used), cpu, cuda, portable.
  void SetDevice(const char* device);
  const char* GetDevice();
  /// The ray marcher or the volume path tracer, named as scene files name them (scene key
  /// integration.integrator), with its medium and lights (the scene's pathtrace keys).
  void SetIntegrator(const char* integrator);
  const char* GetIntegrator();
  void SetAlbedo(double albedo);
  void SetAnisotropy(double g);
  void SetBounces(int bounces);
  void SetEmission(double emission);
  void SetEnvironment(double r, double g, double b);
  /// A sky gradient (pathtrace.sky and pathtrace.ground): off, the environment is uniform.
  void SetSkyGradient(int on);
  void SetSky(double r, double g, double b);
  void SetGround(double r, double g, double b);
  void SetSunDirection(double x, double y, double z);
  void SetSunIntensity(double intensity);
  void SetSunAngle(double degrees);
  ///@}

  ///@{
  /// What the representation did: the models it built (one per input and array), the passes in
  /// the image last drawn (0 for a draft), and where the renderer runs.
  int GetModelBuilds();
  /// What each process holds, as a JSON array of {"rank", "cells" (its part with the halo),
  /// "owned_cells" (cells whose centres lie in its part), "bytes" (bricks, values and regions)}.
  const char* GetPartsInformation();
  int GetRefinementPasses();
  const char* GetDeviceInUse();
  /// The scene document of the last render (exa::writeSceneJson: the view's camera and size, the
  /// layer and transfer function of the colour map and opacity function, iso-values, clip planes,
  /// shading, path tracing, ...); "{}" before the first.
  const char* GetSceneDocument();
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
  /// Passes the sky gradient's properties to the mapper.
  void ApplySky();

  class vtkInternals;
  vtkInternals* Internals;
  vtkVolume* Actor;
  vtkExaBricksVolumeMapper* Mapper;
};
