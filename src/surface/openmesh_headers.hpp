#pragma once
// OpenMesh's headers, included with one GCC warning off. OpenMesh 9's VectorT() leaves its
// coordinates uninitialized on purpose (speed), and its PropertyT<T>::push_back() appends T():
// GCC 12 then reports -Wmaybe-uninitialized inside the inlined std::vector code of every
// vector-valued property (texture coordinates, normals, colors) of the default TriMesh traits.
// The values are placeholders that OpenMesh overwrites before use; the code is OpenMesh's, not
// ours, so the warning is silenced for these headers only (the instantiations are emitted from
// within this region).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
