// The subset of the OpenHaptics HDAPI C ABI that dentsim uses (issue #15), declared here from the
// facts of docs/device_facts.md §5 (vendor headers hd.h, hdDefines.h, hdDevice.h,
// hdScheduler.h of OpenHaptics 3.0/3.3 for Linux), so that the build never needs the SDK.
//
// ABI: plain C on x86-64 Linux (LP64). The vendor headers mark entry points stdcall under
// `#if defined(linux)`, which x86-64 gcc ignores; HDlong/HDulong are 8 bytes. Angles are in rad,
// joint and gimbal torques in mN m (HD_CURRENT_JOINT_TORQUE, HD_CURRENT_GIMBAL_TORQUE), forces in
// N. Only types, constants and function-pointer types live here: the library is loaded at run time
// (hdapi_library.h); the project's emulator (device/hdapi/emulator/) defines the same symbols.
#pragma once

#include <cstddef>
#include <cstdint>

extern "C" {

using HHD = unsigned int;
using HDenum = unsigned int;
using HDerror = unsigned int;
using HDuint = unsigned int;
using HDint = int;
using HDboolean = unsigned char;
using HDushort = unsigned short;
using HDlong = long;
using HDulong = unsigned long;
using HDdouble = double;
using HDfloat = float;
using HDstring = const char*;
using HDCallbackCode = unsigned int;
using HDSchedulerHandle = unsigned long;
using HDWaitCode = unsigned int;

struct HDErrorInfo {
  HDerror errorCode;
  int internalErrorCode;
  HHD hHD;
};

using HDSchedulerCallback = HDCallbackCode (*)(void* user_data);

}  // extern "C"

static_assert(sizeof(HDlong) == 8 && sizeof(HDulong) == 8, "HDAPI ABI: LP64 Linux expected");
static_assert(sizeof(HDErrorInfo) == 12, "HDErrorInfo: {unsigned, int, unsigned}");

namespace dentsim::hd {

// clang-format off
inline constexpr HDerror kSuccess = 0x0000;
inline constexpr HHD kInvalidHandle = 0xFFFFFFFFu;
inline constexpr HDstring kDefaultDevice = nullptr;
inline constexpr HDCallbackCode kCallbackDone = 0;
inline constexpr HDCallbackCode kCallbackContinue = 1;
inline constexpr HDWaitCode kWaitCheckStatus = 0;
inline constexpr HDWaitCode kWaitInfinite = 1;
inline constexpr HDushort kMaxSchedulerPriority = 0xFFFF;
inline constexpr HDushort kDefaultSchedulerPriority = 0x7FFF;

// hdEnable / hdDisable capabilities.
inline constexpr HDenum kForceOutput = 0x4000;
inline constexpr HDenum kMaxForceClamping = 0x4001;
inline constexpr HDenum kForceRamping = 0x4002;
inline constexpr HDenum kSoftwareForceLimit = 0x4003;

// hdGet* / hdSet* parameters.
inline constexpr HDenum kCurrentButtons = 0x2000;
inline constexpr HDenum kCurrentEncoderValues = 0x2010;
inline constexpr HDenum kCurrentPosition = 0x2050;
inline constexpr HDenum kCurrentVelocity = 0x2051;
inline constexpr HDenum kCurrentTransform = 0x2052;
inline constexpr HDenum kCurrentJointAngles = 0x2100;   // 3 doubles [rad]
inline constexpr HDenum kCurrentGimbalAngles = 0x2150;  // 3 doubles [rad]
inline constexpr HDenum kDeviceModelType = 0x2501;      // string
inline constexpr HDenum kDeviceSerialNumber = 0x2504;   // string
inline constexpr HDenum kInputDof = 0x2553;             // int
inline constexpr HDenum kOutputDof = 0x2554;            // int
inline constexpr HDenum kUpdateRate = 0x2600;           // int [Hz]
inline constexpr HDenum kNominalMaxStiffness = 0x2602;  // double [N/mm]
inline constexpr HDenum kNominalMaxForce = 0x2603;      // double [N]
inline constexpr HDenum kNominalMaxContinuousForce = 0x2604;  // double [N]
inline constexpr HDenum kMotorTemperature = 0x2605;     // doubles, normalised 0..1 per motor
inline constexpr HDenum kNominalMaxTorqueStiffness = 0x2620;
inline constexpr HDenum kNominalMaxTorqueDamping = 0x2621;
inline constexpr HDenum kNominalMaxTorqueForce = 0x2622;            // [mN m]
inline constexpr HDenum kNominalMaxTorqueContinuousForce = 0x2623;  // [mN m]
inline constexpr HDenum kCurrentForce = 0x2700;
inline constexpr HDenum kCurrentJointTorque = 0x2703;   // 3 doubles [mN m]
inline constexpr HDenum kCurrentGimbalTorque = 0x2704;  // 3 doubles [mN m]
inline constexpr HDenum kLastJointTorque = 0x2802;
inline constexpr HDenum kLastGimbalTorque = 0x2803;

// Error codes.
inline constexpr HDerror kInvalidEnum = 0x0100;
inline constexpr HDerror kInvalidValue = 0x0101;
inline constexpr HDerror kInvalidOperation = 0x0102;
inline constexpr HDerror kInvalidInputType = 0x0103;
inline constexpr HDerror kBadHandle = 0x0104;
inline constexpr HDerror kWarmMotors = 0x0200;
inline constexpr HDerror kExceededMaxForce = 0x0201;
inline constexpr HDerror kExceededMaxForceImpulse = 0x0202;
inline constexpr HDerror kExceededMaxVelocity = 0x0203;
inline constexpr HDerror kForceError = 0x0204;
inline constexpr HDerror kDeviceFault = 0x0300;
inline constexpr HDerror kDeviceAlreadyInitiated = 0x0301;
inline constexpr HDerror kCommError = 0x0302;
inline constexpr HDerror kCommConfigError = 0x0303;
inline constexpr HDerror kTimerError = 0x0304;
inline constexpr HDerror kIllegalBegin = 0x0400;
inline constexpr HDerror kIllegalEnd = 0x0401;
inline constexpr HDerror kFrameError = 0x0402;
inline constexpr HDerror kInvalidPriority = 0x0500;
inline constexpr HDerror kSchedulerFull = 0x0501;
inline constexpr HDerror kInvalidLicense = 0x0600;
// clang-format on

// The vendor's name of an error code in lower case ("hd_comm_error"), "hd_unknown_error" else.
// These are the fault names dentsim reports (report.json `faults`).
const char* error_name(HDerror code);
// Scheduler errors stop the loop (COMM, COMM_CONFIG, TIMER, INVALID_PRIORITY, SCHEDULER_FULL).
bool is_scheduler_error(HDerror code);
// Force errors: the vendor examples disable force output until they clear (WARM_MOTORS,
// EXCEEDED_MAX_FORCE, EXCEEDED_MAX_VELOCITY, FORCE_ERROR).
bool is_force_error(HDerror code);
// The device fault flag (device.h DeviceFault) of an error code: kFaultHd<Code>, or
// kFaultHdUnknownError for a code not listed above; 0 for kSuccess.
std::uint32_t fault_for_error(HDerror code);

// Function-pointer types of the entry points dentsim resolves.
extern "C" {
using PFN_hdInitDevice = HHD (*)(HDstring);
using PFN_hdDisableDevice = void (*)(HHD);
using PFN_hdMakeCurrentDevice = void (*)(HHD);
using PFN_hdGetError = HDErrorInfo (*)();
using PFN_hdGetErrorString = HDstring (*)(HDerror);
using PFN_hdEnable = void (*)(HDenum);
using PFN_hdDisable = void (*)(HDenum);
using PFN_hdIsEnabled = HDboolean (*)(HDenum);
using PFN_hdBeginFrame = void (*)(HHD);
using PFN_hdEndFrame = void (*)(HHD);
using PFN_hdGetDoublev = void (*)(HDenum, HDdouble*);
using PFN_hdSetDoublev = void (*)(HDenum, const HDdouble*);
using PFN_hdGetIntegerv = void (*)(HDenum, HDint*);
using PFN_hdGetString = HDstring (*)(HDenum);
using PFN_hdStartScheduler = void (*)();
using PFN_hdStopScheduler = void (*)();
using PFN_hdSetSchedulerRate = void (*)(HDulong);
using PFN_hdScheduleAsynchronous = HDSchedulerHandle (*)(HDSchedulerCallback, void*, HDushort);
using PFN_hdScheduleSynchronous = void (*)(HDSchedulerCallback, void*, HDushort);
using PFN_hdUnschedule = void (*)(HDSchedulerHandle);
using PFN_hdWaitForCompletion = HDboolean (*)(HDSchedulerHandle, HDWaitCode);
using PFN_hdGetSchedulerTimeStamp = HDdouble (*)();
}

}  // namespace dentsim::hd
