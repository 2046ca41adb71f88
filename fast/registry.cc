#include "fast/registry.h"

#include <array>

#include "fast/tick.h"
#include "reference/core/io.h"

namespace dentsim {

std::span<const StageTable* const> stage_tables() {
  static const std::array<const StageTable*, 2> kTables = {&reference_stage_table(),
                                                           &fast::fast_stage_table()};
  return kTables;
}

const StageTable* find_stage_table(std::string_view name) {
  for (const StageTable* t : stage_tables()) {
    if (name == t->implementation) return t;
  }
  return nullptr;
}

std::string stage_table_names() {
  std::string s;
  for (const StageTable* t : stage_tables()) {
    if (!s.empty()) s += ", ";
    s += t->implementation;
  }
  return s;
}

std::unique_ptr<Pipeline> make_pipeline(std::string_view name, const SixDofDeviceModel& device,
                                        const PipelineConfig& config) {
  const StageTable* table = find_stage_table(name);
  if (table == nullptr) {
    throw InputError("unknown pipeline '" + std::string(name) +
                     "' (expected one of: " + stage_table_names() + ")");
  }
  return std::make_unique<StagedPipeline>(*table, device, config);
}

}  // namespace dentsim
