#include "fast/registry.h"

#include <array>

#include "fast/friction.h"
#include "fast/phantom/phantom_model.h"
#include "fast/tick.h"
#include "fast/tooth/tooth_contacts.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {

namespace {

template <class Model>
std::unique_ptr<SixDofDeviceModel> make_model(const PhantomParams& params) {
  return std::make_unique<Model>(params);
}

}  // namespace

std::span<const Implementation* const> implementations() {
  // Function-local, so that a caller's static initialiser sees them built.
  static const Implementation kReference{&reference_stage_table(), &make_model<PhantomModel>,
                                         nullptr, &make_reference_tooth,
                                         &solve_with_friction_unchecked};
  static const Implementation kFast{&fast::fast_stage_table(), &make_model<fast::PhantomModel>,
                                    &make_model<fast::PhantomModelFloat>, &fast::make_fast_tooth,
                                    &fast::solve_with_friction_unchecked};
  static const std::array<const Implementation*, 2> kAll = {&kReference, &kFast};
  return kAll;
}

const Implementation* find_implementation(std::string_view name) {
  for (const Implementation* i : implementations()) {
    if (name == i->name()) return i;
  }
  return nullptr;
}

const Implementation& implementation(std::string_view name) {
  const Implementation* i = find_implementation(name);
  if (i == nullptr) {
    throw InputError("unknown pipeline '" + std::string(name) +
                     "' (expected one of: " + stage_table_names() + ")");
  }
  return *i;
}

std::span<const StageTable* const> stage_tables() {
  static const std::array<const StageTable*, 2> kTables = [] {
    std::array<const StageTable*, 2> t{};
    for (std::size_t k = 0; k < t.size(); ++k) t[k] = implementations()[k]->stages;
    return t;
  }();
  return kTables;
}

const StageTable* find_stage_table(std::string_view name) {
  const Implementation* i = find_implementation(name);
  return i == nullptr ? nullptr : i->stages;
}

std::string stage_table_names() {
  std::string s;
  for (const Implementation* i : implementations()) {
    if (!s.empty()) s += ", ";
    s += i->name();
  }
  return s;
}

std::vector<std::string> implementation_names() {
  std::vector<std::string> names;
  for (const Implementation* i : implementations()) names.emplace_back(i->name());
  return names;
}

std::unique_ptr<Pipeline> make_pipeline(std::string_view name, const SixDofDeviceModel& device,
                                        const PipelineConfig& config) {
  return std::make_unique<StagedPipeline>(*implementation(name).stages, device, config);
}

std::unique_ptr<SixDofDeviceModel> make_phantom_model(std::string_view name,
                                                      const PhantomParams& params,
                                                      bool float_terms) {
  const Implementation& impl = implementation(name);
  if (!float_terms) return impl.phantom_model(params);
  if (impl.phantom_model_float == nullptr) {
    std::string with;
    for (const Implementation* i : implementations()) {
      if (i->phantom_model_float == nullptr) continue;
      if (!with.empty()) with += ", ";
      with += i->name();
    }
    throw InputError("float device terms exist in the " + with + " pipeline only (got pipeline '" +
                     std::string(name) + "')");
  }
  return impl.phantom_model_float(params);
}

}  // namespace dentsim
