// The one pybind11 module over the C++ core, `mbot_slam_navigation._core`: one binding function per
// area (bindings.h). Conversions to and from numpy happen in the binding files, at the boundary.
#include "bindings.h"

PYBIND11_MODULE(_core, m) {
  m.doc() = "C++ core of mbot_slam_navigation (private: use the wrappers in mbot_slam_navigation)";
  using namespace mbot::bindings;
  bindAmcl(m);
  bindGrid(m);
  bindSimulation(m);
  bindSlam(m);
  bindCostmaps(m);
  bindLocalPlanner(m);
  bindNavigation(m);
}
