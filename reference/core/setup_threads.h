// Threads for the setup's builds (issue #30: the field model's setup of a 512^3 tooth in <= 10 s
// on the 2-core machines the project targets): the tooth field's surface and samples are built on
// several threads, each on a disjoint part, so that the result is the one-thread build's, bit for
// bit, whatever the thread count (tests/tooth/sampled_field_test.cc, ThreadedBuild*); so are the
// procedural molar's voxels and the enamel's distance transform and materials (tooth_io/
// voxelize.cc edt_box, assign_materials; tests/tooth_io/voxelize_test.cc, Materials.Threaded*).
//
// The count: the environment variable DENTSIM_SETUP_THREADS (a whole number >= 1) when set, else
// std::thread::hardware_concurrency() capped at kMaxSetupThreads (docs/scenes.md, under
// tooth.contact_model).
// Never used inside a servo tick (it starts threads).
#pragma once

#include <functional>

namespace dentsim {

inline constexpr int kMaxSetupThreads = 8;

// The setup's thread count (header comment). Throws InputError when DENTSIM_SETUP_THREADS is set
// to anything but a whole number in [1, 1024].
int setup_threads();

// Runs task(i) once for every i in [0, count) on min(threads, count) threads, the calling thread
// among them (threads <= 0: setup_threads()); the tasks are taken in order from a shared counter,
// so a task must write only what no other task touches. The first exception a task throws is
// rethrown here after every thread has stopped.
void parallel_tasks(int count, int threads, const std::function<void(int)>& task);

}  // namespace dentsim
