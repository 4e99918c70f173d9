#pragma once
// LCM channel names and the default URL. CHANNELS.md beside this file documents types and rates.
namespace vitreo::telemetry {

// Multicast on loopback only: ttl=0 keeps every packet on this machine.
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

inline constexpr const char* kChanInstrumentState = "VITREO_INSTRUMENT_STATE";
inline constexpr const char* kChanDeviceStatus = "VITREO_DEVICE_STATUS";
inline constexpr const char* kChanPhysicsTiming = "VITREO_PHYSICS_TIMING";
inline constexpr const char* kChanEvent = "VITREO_EVENT";
inline constexpr const char* kChanScore = "VITREO_SCORE";
inline constexpr const char* kChanCriteria = "VITREO_CRITERIA";
inline constexpr const char* kChanTotals = "VITREO_TOTALS";
inline constexpr const char* kChanControls = "VITREO_CONTROLS";
inline constexpr const char* kChanCommand = "VITREO_COMMAND";
inline constexpr const char* kChanCommandAck = "VITREO_COMMAND_ACK";
inline constexpr const char* kChanRecHeader = "VITREO_REC_HEADER";
inline constexpr const char* kChanRecInput = "VITREO_REC_INPUT";
inline constexpr const char* kChanRecCheck = "VITREO_REC_CHECK";
inline constexpr const char* kChanRecEnd = "VITREO_REC_END";
inline constexpr const char* kChanReceiveStatus = "VITREO_RECEIVE_STATUS";

}  // namespace vitreo::telemetry
