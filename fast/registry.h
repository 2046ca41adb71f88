// The registry of the tick's implementations (docs/design.md "One registry", "The tick as
// Model/Data stages"): every StageTable implementing the stage list of reference/core/pipeline.h.
// The differential tests, the benchmarks, the allocation-counting test and `--pipeline NAME` all
// iterate this one list, so no implementation of a stage can exist without being checked.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "reference/tick.h"

namespace dentsim {

// Every implementation, the reference first.
std::span<const StageTable* const> stage_tables();
// The table named `name` ("reference", "fast"), or nullptr.
const StageTable* find_stage_table(std::string_view name);
// "reference, fast": the names, for messages and --help.
std::string stage_table_names();
// A pipeline of the named implementation over `device` (StagedPipeline). Throws InputError for an
// unknown name (listing the known ones) and what make_pipeline_model throws for a bad config.
std::unique_ptr<Pipeline> make_pipeline(std::string_view name, const SixDofDeviceModel& device,
                                        const PipelineConfig& config);

}  // namespace dentsim
