// Run-time loading of the OpenHaptics HDAPI library (issue #15; docs/device_facts.md §5).
//
// Where the library comes from, first match wins:
//   1. an explicit path (`--hd-library PATH`),
//   2. the environment variable DENTSIM_HD_LIBRARY,
//   3. the usual sonames, in order: libHD.so, libHD.so.3.0, libHD.so.3, libHD.so.3.3.0 (installs
//      may ship only the versioned name), looked up by the dynamic loader (LD_LIBRARY_PATH,
//      ld.so.cache, /usr/lib...), then /usr/lib/libHD.so and /opt/OpenHaptics/... copies.
// Every entry point of hdapi_abi.h is resolved with dlsym and checked; a library missing one is
// rejected with the symbol named. On failure the error lists every place tried and why it failed
// (dlerror()).
//
// Field fact (CHAI3D): the vendor library fails when loaded a second time, so a loaded library is
// never dlclose()d: it is kept for the life of the process, one per path.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "device/hdapi/hdapi_abi.h"

namespace dentsim {

// A failure of the HDAPI backend (library not found, device not initialised, HD error).
class HdapiError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct HdLibrary {
  std::string path;  // what dlopen was given
  void* handle = nullptr;
  hd::PFN_hdInitDevice hdInitDevice = nullptr;
  hd::PFN_hdDisableDevice hdDisableDevice = nullptr;
  hd::PFN_hdMakeCurrentDevice hdMakeCurrentDevice = nullptr;
  hd::PFN_hdGetError hdGetError = nullptr;
  hd::PFN_hdGetErrorString hdGetErrorString = nullptr;
  hd::PFN_hdEnable hdEnable = nullptr;
  hd::PFN_hdDisable hdDisable = nullptr;
  hd::PFN_hdIsEnabled hdIsEnabled = nullptr;
  hd::PFN_hdBeginFrame hdBeginFrame = nullptr;
  hd::PFN_hdEndFrame hdEndFrame = nullptr;
  hd::PFN_hdGetDoublev hdGetDoublev = nullptr;
  hd::PFN_hdSetDoublev hdSetDoublev = nullptr;
  hd::PFN_hdGetIntegerv hdGetIntegerv = nullptr;
  hd::PFN_hdGetString hdGetString = nullptr;
  hd::PFN_hdStartScheduler hdStartScheduler = nullptr;
  hd::PFN_hdStopScheduler hdStopScheduler = nullptr;
  hd::PFN_hdSetSchedulerRate hdSetSchedulerRate = nullptr;
  hd::PFN_hdScheduleAsynchronous hdScheduleAsynchronous = nullptr;
  hd::PFN_hdScheduleSynchronous hdScheduleSynchronous = nullptr;
  hd::PFN_hdUnschedule hdUnschedule = nullptr;
  hd::PFN_hdWaitForCompletion hdWaitForCompletion = nullptr;
  hd::PFN_hdGetSchedulerTimeStamp hdGetSchedulerTimeStamp = nullptr;
};

// The candidates tried for `explicit_path` ("" = none) in order (see the header comment).
std::vector<std::string> hd_library_candidates(const std::string& explicit_path);

// Loads (once per path, never unloaded) the first candidate that opens and exports every symbol.
// Throws HdapiError listing each candidate and why it failed. An explicit path or
// DENTSIM_HD_LIBRARY is the only candidate when given: a wrong override is not silently replaced
// by another library.
const HdLibrary& load_hd_library(const std::string& explicit_path);

}  // namespace dentsim
