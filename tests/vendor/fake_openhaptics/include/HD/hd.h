/* A stand-in for the OpenHaptics HD API header, written for this project's tests: it declares
 * the subset of the API that client/device/vendor/vendor_sdk_device.cpp calls, with the types and
 * signatures of the SDK's documentation, so that the driver skeleton compiles and runs here
 * against a simulated device (fake_hd.cpp). Parameter codes are this fake's own values. It is
 * not the vendor's header and carries none of its text; a real build uses the SDK's. */
#ifndef TELEOP_FAKE_HD_H
#define TELEOP_FAKE_HD_H

#ifdef __cplusplus
extern "C" {
#endif

typedef unsigned int HHD;
typedef double HDdouble;
typedef int HDint;
typedef unsigned int HDenum;
typedef unsigned int HDerror;
typedef unsigned char HDboolean;
typedef unsigned short HDushort;
typedef const char* HDstring;
typedef unsigned long HDSchedulerHandle;
typedef unsigned int HDCallbackCode;

#define HDCALLBACK
typedef HDCallbackCode(HDCALLBACK* HDSchedulerCallback)(void* user_data);

typedef struct {
  HDerror errorCode;
  int internalErrorCode;
  HHD hHD;
} HDErrorInfo;

#define HD_SUCCESS 0x0000
#define HD_DEVICE_FAULT 0x0100
#define HD_INVALID_HANDLE 0x0200
#define HD_DEVICE_ERROR(info) ((info).errorCode != HD_SUCCESS)
#define HD_DEFAULT_DEVICE ((HDstring)0)
#define HD_INVALID_HANDLE_VALUE 0xFFFFFFFFu

#define HD_CALLBACK_DONE 0
#define HD_CALLBACK_CONTINUE 1
#define HD_MAX_SCHEDULER_PRIORITY 0xFFFF

/* capabilities */
#define HD_FORCE_OUTPUT 0x4000
/* state and properties (this fake's codes) */
#define HD_CURRENT_BUTTONS 0x2000
#define HD_CURRENT_POSITION 0x2050
#define HD_CURRENT_VELOCITY 0x2051
#define HD_CURRENT_TRANSFORM 0x2052
#define HD_CURRENT_FORCE 0x2700
#define HD_USABLE_WORKSPACE_DIMENSIONS 0x2550
#define HD_NOMINAL_MAX_FORCE 0x2603
#define HD_NOMINAL_MAX_CONTINUOUS_FORCE 0x2604
#define HD_NOMINAL_MAX_STIFFNESS 0x2602
#define HD_NOMINAL_MAX_DAMPING 0x2609
#define HD_DEVICE_MODEL_TYPE 0x2501

HHD hdInitDevice(HDstring config_name);
void hdDisableDevice(HHD hhd);
void hdMakeCurrentDevice(HHD hhd);
HDErrorInfo hdGetError(void);
HDstring hdGetErrorString(HDerror code);
void hdGetDoublev(HDenum name, HDdouble* values);
void hdGetIntegerv(HDenum name, HDint* values);
HDstring hdGetString(HDenum name);
void hdSetDoublev(HDenum name, const HDdouble* values);
void hdEnable(HDenum cap);
void hdDisable(HDenum cap);
void hdBeginFrame(HHD hhd);
void hdEndFrame(HHD hhd);
HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback callback, void* user_data,
                                         HDushort priority);
void hdUnschedule(HDSchedulerHandle handle);
void hdStartScheduler(void);
void hdStopScheduler(void);

#ifdef __cplusplus
}
#endif

#endif
