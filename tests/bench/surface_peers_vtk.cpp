#include "surface_peers_vtk.hpp"

#include <vtkFloatArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSMPTools.h>

namespace benchpeers {

struct FlyingEdgesState {
  vtkNew<vtkImageData> image;
  vtkNew<vtkFloatArray> scalars;
  vtkNew<vtkFlyingEdges3D> filter;
};

void setThreads(int threads) { vtkSMPTools::Initialize(threads); }

FlyingEdges::FlyingEdges() : state_(std::make_unique<FlyingEdgesState>()) {}
FlyingEdges::~FlyingEdges() = default;

std::size_t FlyingEdges::run(float* lattice, const int dims[3], double spacing, const double origin[3], float value,
                             bool normals) {
  FlyingEdgesState& s = *state_;
  s.image->SetDimensions(dims[0], dims[1], dims[2]);
  s.image->SetSpacing(spacing, spacing, spacing);
  s.image->SetOrigin(origin[0], origin[1], origin[2]);
  s.scalars->SetArray(lattice, vtkIdType(dims[0]) * dims[1] * dims[2], 1);  // borrowed, not freed by VTK
  s.image->GetPointData()->SetScalars(s.scalars);
  s.image->Modified();
  s.filter->SetInputData(s.image);
  s.filter->SetValue(0, value);
  s.filter->SetComputeNormals(normals);
  s.filter->ComputeGradientsOff();
  s.filter->ComputeScalarsOff();
  s.filter->Modified();
  s.filter->Update();
  return std::size_t(s.filter->GetOutput()->GetNumberOfPolys());
}

}  // namespace benchpeers
