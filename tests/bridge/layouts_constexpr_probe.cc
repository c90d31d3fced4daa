// Compiled (not linked) by layouts_compile_test.cmake, twice: as it is, the
// index of a field of the table is a compile-time constant; with
// VLAB_PROBE_UNKNOWN_FIELD, a misspelt field name must not compile.
#include "bridge/bridge_layouts.h"

#ifdef VLAB_PROBE_UNKNOWN_FIELD
constexpr const char* kField = "grasp";
#else
constexpr const char* kField = "grasped";
#endif

constexpr int kGrasped = vlab::bridge::StateIndex(vlab::bridge::DeviceKind::kGripper, kField);
static_assert(kGrasped == 4);

int main() { return kGrasped; }
