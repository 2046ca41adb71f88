#include "device/hdapi/hdapi_library.h"

#include <dlfcn.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>

namespace dentsim {

std::vector<std::string> hd_library_candidates(const std::string& explicit_path) {
  if (!explicit_path.empty()) return {explicit_path};
  if (const char* env = std::getenv("DENTSIM_HD_LIBRARY"); env != nullptr && *env != '\0') {
    return {env};
  }
  return {"libHD.so",
          "libHD.so.3.0",
          "libHD.so.3",
          "libHD.so.3.3.0",
          "/usr/lib/libHD.so",
          "/usr/lib64/libHD.so",
          "/usr/lib/x86_64-linux-gnu/libHD.so",
          "/opt/OpenHaptics/Developer/lib/lin-x86_64/libHD.so",
          "/opt/OpenHaptics/lib/libHD.so"};
}

namespace {

template <typename Fn>
bool resolve(void* handle, const char* name, Fn& out, std::string& why) {
  dlerror();
  void* p = dlsym(handle, name);
  const char* err = dlerror();
  if (p == nullptr || err != nullptr) {
    if (why.empty()) why = "does not export";
    why += std::string(" ") + name;
    return false;
  }
  static_assert(sizeof(Fn) == sizeof(void*));
  std::memcpy(&out, &p, sizeof p);  // dlsym returns functions as object pointers (POSIX)
  return true;
}

// Resolves every symbol; `why` names the missing ones.
bool resolve_all(HdLibrary& l, std::string& why) {
  bool ok = true;
  ok &= resolve(l.handle, "hdInitDevice", l.hdInitDevice, why);
  ok &= resolve(l.handle, "hdDisableDevice", l.hdDisableDevice, why);
  ok &= resolve(l.handle, "hdMakeCurrentDevice", l.hdMakeCurrentDevice, why);
  ok &= resolve(l.handle, "hdGetError", l.hdGetError, why);
  ok &= resolve(l.handle, "hdGetErrorString", l.hdGetErrorString, why);
  ok &= resolve(l.handle, "hdEnable", l.hdEnable, why);
  ok &= resolve(l.handle, "hdDisable", l.hdDisable, why);
  ok &= resolve(l.handle, "hdIsEnabled", l.hdIsEnabled, why);
  ok &= resolve(l.handle, "hdBeginFrame", l.hdBeginFrame, why);
  ok &= resolve(l.handle, "hdEndFrame", l.hdEndFrame, why);
  ok &= resolve(l.handle, "hdGetDoublev", l.hdGetDoublev, why);
  ok &= resolve(l.handle, "hdSetDoublev", l.hdSetDoublev, why);
  ok &= resolve(l.handle, "hdGetIntegerv", l.hdGetIntegerv, why);
  ok &= resolve(l.handle, "hdGetString", l.hdGetString, why);
  ok &= resolve(l.handle, "hdStartScheduler", l.hdStartScheduler, why);
  ok &= resolve(l.handle, "hdStopScheduler", l.hdStopScheduler, why);
  ok &= resolve(l.handle, "hdSetSchedulerRate", l.hdSetSchedulerRate, why);
  ok &= resolve(l.handle, "hdScheduleAsynchronous", l.hdScheduleAsynchronous, why);
  ok &= resolve(l.handle, "hdScheduleSynchronous", l.hdScheduleSynchronous, why);
  ok &= resolve(l.handle, "hdUnschedule", l.hdUnschedule, why);
  ok &= resolve(l.handle, "hdWaitForCompletion", l.hdWaitForCompletion, why);
  ok &= resolve(l.handle, "hdGetSchedulerTimeStamp", l.hdGetSchedulerTimeStamp, why);
  return ok;
}

}  // namespace

const HdLibrary& load_hd_library(const std::string& explicit_path) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<HdLibrary>> loaded;
  const std::lock_guard<std::mutex> lock(mutex);
  const std::vector<std::string> candidates = hd_library_candidates(explicit_path);
  std::string report;
  for (const std::string& c : candidates) {
    if (auto it = loaded.find(c); it != loaded.end()) return *it->second;
    dlerror();
    void* h = dlopen(c.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (h == nullptr) {
      const char* err = dlerror();
      report += "\n  " + c + ": " + (err != nullptr ? err : "dlopen failed");
      continue;
    }
    auto lib = std::make_unique<HdLibrary>();
    lib->path = c;
    lib->handle = h;
    std::string why;
    if (!resolve_all(*lib, why)) {
      // Not the HDAPI (or an incomplete one): keep it loaded anyway (never dlclose, see header).
      report += "\n  " + c + ": opened, but " + why;
      continue;
    }
    return *loaded.emplace(c, std::move(lib)).first->second;
  }
  std::string where =
      !explicit_path.empty() ? "--hd-library"
      : std::getenv("DENTSIM_HD_LIBRARY") != nullptr && *std::getenv("DENTSIM_HD_LIBRARY") != '\0'
          ? "DENTSIM_HD_LIBRARY"
          : "the usual sonames";
  throw HdapiError("OpenHaptics library (HDAPI) not found; tried " + where + ":" + report +
                   "\n  (install OpenHaptics / the Phantom device driver, or give the library "
                   "with --hd-library PATH or DENTSIM_HD_LIBRARY; the project's emulator is "
                   "libdentsim_hd_emulator.so in the build directory)");
}

}  // namespace dentsim
