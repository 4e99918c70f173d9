#pragma once
// SIGINT (Ctrl-C) and SIGTERM (`systemctl stop`) end a session gracefully: the first one is noted
// in an atomic the physics step reads (rig::SessionConfig::stop), so the session finishes its step,
// records its end, flushes and syncs, prints its summary and exits 0. A second one forces: the
// default action runs at once (the recording then reads as truncated, up to its last checksum).
#include <atomic>

namespace vitreo::app {

// Installs the handlers; `flag` receives the first signal's number. Call once.
void install_stop_signals(std::atomic<int>& flag);

}  // namespace vitreo::app
