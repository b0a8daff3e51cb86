#pragma once
// SIGINT/SIGTERM handling: handlers only set a flag; loops poll stop_requested().
namespace teleop {
/// Installs the handlers (idempotent).
void install_stop_signal_handlers();
/// True once SIGINT or SIGTERM has been received (or request_stop() called).
bool stop_requested();
void request_stop();
}  // namespace teleop
