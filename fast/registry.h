// The registry of the tick's implementations (docs/design.md "One registry"; docs/pipeline.md
// "One registry of implementations"): one entry per implementation of the stage list of
// reference/core/pipeline.h, with what a caller plugs into it: the stage table, the device model
// that evaluates a Phantom model file's terms, and the tooth its collide and drill stages query
// (per contact model). A caller looks its
// implementation up once by name; nothing else compares implementation names. The differential
// tests, the benchmarks, the allocation-counting test and `--pipeline NAME` all iterate this one
// list, so no implementation of a stage can exist without being checked; adding one is one entry
// in registry.cc.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "reference/phantom/phantom_params.h"
#include "reference/tick.h"
#include "reference/tooth/tooth_contacts.h"

namespace dentsim {

struct Implementation {
  const StageTable* stages = nullptr;  // its name: stages->implementation
  // The implementation's evaluation of the terms of the Phantom that `params` describe.
  std::unique_ptr<SixDofDeviceModel> (*phantom_model)(const PhantomParams& params) = nullptr;
  // The same in single precision (a speed/accuracy trade-off, `dentsim bench`); null when the
  // implementation has none.
  std::unique_ptr<SixDofDeviceModel> (*phantom_model_float)(const PhantomParams& params) = nullptr;
  // The implementation's tooth over the reference tooth `tooth` (which must outlive it).
  std::unique_ptr<PipelineTooth> (*tooth)(VoxelTooth& tooth,
                                          const PipelineToothSetup& setup) = nullptr;
  // The friction solve its solve stage runs (reference/friction.h's contract): compared with the
  // reference's by tests/fast/friction_test.cc and timed by bench/tick_bench.cc (BM_Friction).
  FrictionSolve friction = nullptr;

  const char* name() const { return stages->implementation; }
};

// Every implementation, the reference first.
std::span<const Implementation* const> implementations();
// The implementation named `name` ("reference", "fast"), or nullptr.
const Implementation* find_implementation(std::string_view name);
// The same; throws InputError naming `name` and listing the known ones.
const Implementation& implementation(std::string_view name);

// The implementations' stage tables, in the same order.
std::span<const StageTable* const> stage_tables();
// The table named `name`, or nullptr.
const StageTable* find_stage_table(std::string_view name);
// "reference, fast": the names, for messages and --help.
std::string stage_table_names();
// The names, in the registry's order (e.g. for a command-line option's allowed values).
std::vector<std::string> implementation_names();
// A pipeline of the named implementation over `device` (StagedPipeline). Throws InputError for an
// unknown name (listing the known ones) and what make_pipeline_model throws for a bad config.
std::unique_ptr<Pipeline> make_pipeline(std::string_view name, const SixDofDeviceModel& device,
                                        const PipelineConfig& config);
// The named implementation's evaluation of the Phantom `params` describe, in double or, with
// `float_terms`, single precision. Throws InputError for an unknown name or for single precision
// where the implementation has none.
std::unique_ptr<SixDofDeviceModel> make_phantom_model(std::string_view name,
                                                      const PhantomParams& params,
                                                      bool float_terms = false);

}  // namespace dentsim
