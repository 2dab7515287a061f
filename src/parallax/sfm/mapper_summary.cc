#include "parallax/sfm/mapper_summary.h"

namespace parallax {

std::vector<std::pair<const char*, double>> MapperPhaseSeconds::Named() const {
  return {{"next_view", next_view},         {"registration", registration},
          {"triangulation", triangulation}, {"local_ba", local_ba},
          {"global_ba", global_ba},         {"filtering", filtering},
          {"completion", completion},       {"retriangulation", retriangulation}};
}

double MapperPhaseSeconds::Total() const {
  double total = 0;
  for (const auto& [name, seconds] : Named()) total += seconds;
  return total;
}

}  // namespace parallax
