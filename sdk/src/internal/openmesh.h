// OpenMesh's headers, for the SDK's adapters (the decimation). Their asserts are left out in every
// build: they check OpenMesh's own invariants, and in a Debug build each property access builds
// the property's type name as a std::string to compare it, an allocation per access (under the
// sanitizers, which record a stack per allocation, that made the decimation most of a scan's
// model build). The SDK's own asserts are unaffected: <cassert> is included again after them.
#pragma once

#ifndef NDEBUG
#define STRATA_OPENMESH_NDEBUG
#define NDEBUG
#include <cassert>
#endif

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#ifdef STRATA_OPENMESH_NDEBUG
#undef STRATA_OPENMESH_NDEBUG
#undef NDEBUG
#include <cassert>
#endif
