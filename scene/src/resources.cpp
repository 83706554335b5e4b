// What a scene will cost before it runs (resources.hpp).
#include <wbm/scene/resources.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <unistd.h>

namespace wbm::scene {

ResourceEstimate estimate_resources(const Scene& scene) {
  ResourceEstimate e;
  if (!scene.structure) return e;
  const double n = scene.structure->dofs();
  const double dofs_out = std::max<double>(1.0, static_cast<double>(scene.output_dofs().size()));
  e.output_bytes = 24.0 * static_cast<double>(scene.output.samples) * (2.0 + 2.0 * dofs_out + 4.0);
  const AnalysisKind kind = scene.analysis.kind;
  if (kind != AnalysisKind::Solve && kind != AnalysisKind::Continuation) return e;
  const double m = scene.basis.dimension;
  const bool fourier = scene.basis.trial == "fourier" && scene.basis.weighting == "fourier";
  const double modal = 8.0 * n * n;
  const double time = (fourier ? 40.0 : 100.0) * m * m;
  const double stacked = 400.0 * n * m;
  const double delassus = scene.rigid() ? 16.0 * std::pow(static_cast<double>(scene.contacts.size()) * m, 2) : 0.0;
  e.memory_bytes = modal + time + stacked + delassus;
  const bool rod = scene.structure->kind == StructureKind::Rod;
  if (modal >= time && modal >= stacked && modal >= delassus) {
    e.memory_key = rod ? "structure.elements" : "structure (the number of DOFs)";
  } else {
    e.memory_key = scene.basis.harmonics > 0 ? "basis.harmonics" : "basis.dimension";
  }
  return e;
}

double physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? static_cast<double>(pages) * static_cast<double>(size) : 0.0;
}

std::string format_bytes(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 6) {
    bytes /= 1000.0;
    ++u;
  }
  char text[32];
  std::snprintf(text, sizeof text, bytes < 10.0 ? "%.1f %s" : "%.0f %s", bytes, units[u]);
  return text;
}

}  // namespace wbm::scene
