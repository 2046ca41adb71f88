#include "device/hdapi/hdapi_abi.h"

#include "device/device.h"

namespace dentsim::hd {

const char* error_name(HDerror code) {
  switch (code) {
    case kSuccess:
      return "hd_success";
    case kInvalidEnum:
      return "hd_invalid_enum";
    case kInvalidValue:
      return "hd_invalid_value";
    case kInvalidOperation:
      return "hd_invalid_operation";
    case kInvalidInputType:
      return "hd_invalid_input_type";
    case kBadHandle:
      return "hd_bad_handle";
    case kWarmMotors:
      return "hd_warm_motors";
    case kExceededMaxForce:
      return "hd_exceeded_max_force";
    case kExceededMaxForceImpulse:
      return "hd_exceeded_max_force_impulse";
    case kExceededMaxVelocity:
      return "hd_exceeded_max_velocity";
    case kForceError:
      return "hd_force_error";
    case kDeviceFault:
      return "hd_device_fault";
    case kDeviceAlreadyInitiated:
      return "hd_device_already_initiated";
    case kCommError:
      return "hd_comm_error";
    case kCommConfigError:
      return "hd_comm_config_error";
    case kTimerError:
      return "hd_timer_error";
    case kIllegalBegin:
      return "hd_illegal_begin";
    case kIllegalEnd:
      return "hd_illegal_end";
    case kFrameError:
      return "hd_frame_error";
    case kInvalidPriority:
      return "hd_invalid_priority";
    case kSchedulerFull:
      return "hd_scheduler_full";
    case kInvalidLicense:
      return "hd_invalid_license";
    default:
      return "hd_unknown_error";
  }
}

bool is_scheduler_error(HDerror code) {
  return code == kCommError || code == kCommConfigError || code == kTimerError ||
         code == kInvalidPriority || code == kSchedulerFull;
}

bool is_force_error(HDerror code) {
  return code == kWarmMotors || code == kExceededMaxForce || code == kExceededMaxVelocity ||
         code == kForceError;
}

std::uint32_t fault_for_error(HDerror code) {
  switch (code) {
    case kSuccess:
      return kFaultNone;
    case kInvalidEnum:
      return kFaultHdInvalidEnum;
    case kInvalidValue:
      return kFaultHdInvalidValue;
    case kInvalidOperation:
      return kFaultHdInvalidOperation;
    case kInvalidInputType:
      return kFaultHdInvalidInputType;
    case kBadHandle:
      return kFaultHdBadHandle;
    case kWarmMotors:
      return kFaultHdWarmMotors;
    case kExceededMaxForce:
      return kFaultHdExceededMaxForce;
    case kExceededMaxForceImpulse:
      return kFaultHdExceededMaxForceImpulse;
    case kExceededMaxVelocity:
      return kFaultHdExceededMaxVelocity;
    case kForceError:
      return kFaultHdForceError;
    case kDeviceFault:
      return kFaultHdDeviceFault;
    case kDeviceAlreadyInitiated:
      return kFaultHdDeviceAlreadyInitiated;
    case kCommError:
      return kFaultHdCommError;
    case kCommConfigError:
      return kFaultHdCommConfigError;
    case kTimerError:
      return kFaultHdTimerError;
    case kIllegalBegin:
      return kFaultHdIllegalBegin;
    case kIllegalEnd:
      return kFaultHdIllegalEnd;
    case kFrameError:
      return kFaultHdFrameError;
    case kInvalidPriority:
      return kFaultHdInvalidPriority;
    case kSchedulerFull:
      return kFaultHdSchedulerFull;
    case kInvalidLicense:
      return kFaultHdInvalidLicense;
    default:
      return kFaultHdUnknownError;
  }
}

}  // namespace dentsim::hd
