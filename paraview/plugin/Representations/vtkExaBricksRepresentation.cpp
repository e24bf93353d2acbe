#include "vtkExaBricksRepresentation.h"

#include "amr_cells.h"
#include "vtkExaBricksVolumeMapper.h"

#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"

#include "vtkDataObject.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMath.h"
#include "vtkObjectFactory.h"
#include "vtkOverlappingAMR.h"
#include "vtkPVRenderView.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <memory>
#include <string>

class vtkExaBricksRepresentation::vtkInternals {
public:
  vtkSmartPointer<vtkOverlappingAMR> Data; ///< the input as RequestData last took it
  unsigned long Generation = 0;            ///< counts the inputs taken
  double Bounds[6] = {0, 0, 0, 0, 0, 0};
  std::shared_ptr<exa::paraview::Engine> Engine;
  std::string BuiltField;
  unsigned long BuiltGeneration = 0;
};

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
  os << indent << "Field: " << this->Internals->BuiltField << "\n";
}

int vtkExaBricksRepresentation::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkOverlappingAMR");
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

int vtkExaBricksRepresentation::RequestData(vtkInformation* request, vtkInformationVector** inputs,
                                            vtkInformationVector* outputs) {
  vtkInternals& in = *this->Internals;
  vtkMath::UninitializeBounds(in.Bounds);
  in.Data = nullptr;
  if (inputs[0]->GetNumberOfInformationObjects() == 1) {
    if (vtkOverlappingAMR* amr = vtkOverlappingAMR::GetData(inputs[0], 0)) {
      in.Data = vtkSmartPointer<vtkOverlappingAMR>::New();
      in.Data->ShallowCopy(amr);
      amr->GetBounds(in.Bounds);
    }
  }
  ++in.Generation;
  return this->Superclass::RequestData(request, inputs, outputs);
}

int vtkExaBricksRepresentation::ProcessViewRequest(vtkInformationRequestKey* request, vtkInformation* inInfo,
                                                   vtkInformation* outInfo) {
  if (!this->Superclass::ProcessViewRequest(request, inInfo, outInfo)) return 0;
  if (request == vtkPVView::REQUEST_UPDATE()) {
    vtkPVRenderView::SetGeometryBounds(inInfo, this, this->Internals->Bounds);
    // The cells stay where they were read: render there.
    vtkPVRenderView::SetRequiresDistributedRendering(inInfo, this, true);
  } else if (request == vtkPVView::REQUEST_RENDER()) {
    this->UpdateEngine();
  }
  return 1;
}

void vtkExaBricksRepresentation::UpdateEngine() {
  vtkInternals& in = *this->Internals;
  vtkInformation* info = this->GetInputArrayInformation(0);
  const char* name = info && info->Has(vtkDataObject::FIELD_NAME()) ? info->Get(vtkDataObject::FIELD_NAME()) : nullptr;
  if (!in.Data || !name || !*name) {
    in.Engine.reset();
    this->Mapper->SetEngine(nullptr);
    return;
  }
  if (in.Engine && in.BuiltField == name && in.BuiltGeneration == in.Generation) return;
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
    auto engine = std::make_shared<exa::paraview::Engine>();
    engine->field = name;
    engine->model = std::make_unique<exa::Model>(exa::buildModel(exa::paraview::amrLeafCells(in.Data, name)));
    engine->renderer = std::make_unique<exa::Renderer>(*engine->model);
    std::copy(in.Bounds, in.Bounds + 6, engine->bounds);
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
