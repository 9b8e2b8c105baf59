// The SIGINT/SIGTERM stop flag of the programs: the handler records the signal, the program's
// loops ask stop_requested() and stop cleanly.
//
// The handler is installed with sigaction(), never signal(): the executables that call METIS
// (peritwin, peritwin-replay, peritwin-stream) link core/signal_guard.cpp, whose
// __sysv_signal refuses every change of SIGTERM (GKlib traps SIGTERM with signal() during each
// METIS call); sigaction() is not interposed, so the handler installed here stays in place.
#pragma once

namespace peritwin::core {

/// Installs the handler for SIGINT and SIGTERM (sigaction, empty mask, no flags).
void install_stop_handler();
/// The last SIGINT/SIGTERM received since install_stop_handler(); 0 when none.
int stop_signal();
/// stop_signal() != 0.
inline bool stop_requested() { return stop_signal() != 0; }
/// !stop_requested(): the `keep_going` callback of the loops that wait (e.g. for an LCM hub).
inline bool keep_running() { return stop_signal() == 0; }

}  // namespace peritwin::core
