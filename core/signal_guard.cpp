// Linked into the peritwin and peritwin-replay executables (not into the libraries).
//
// GKlib (METIS, which CHOLMOD's fill-reducing ordering calls) traps SIGTERM during every METIS
// call with signal(SIGTERM, gk_sigthrow) and restores the previous handler afterwards.
// gk_sigthrow longjmps into thread-local state of the thread inside METIS, so a SIGTERM that
// arrives meanwhile (on any thread), or a restore lost because two threads ran METIS at once
// (the remaining-life simulations do), crashes the process instead of letting it checkpoint
// and stop. The executables therefore interpose glibc's __sysv_signal (what GKlib's signal()
// calls compile to) and refuse changes to SIGTERM; all other signals pass through unchanged.
// The executables install their own SIGTERM/SIGINT handlers with sigaction().
#include <csignal>

extern "C" __sighandler_t __sysv_signal(int sig, __sighandler_t handler) {
  struct sigaction old {};
  if (sig == SIGTERM) {
    if (sigaction(SIGTERM, nullptr, &old) < 0) return SIG_ERR;
    return old.sa_handler;
  }
  struct sigaction sa {};
  sa.sa_handler = handler;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = static_cast<int>(SA_RESETHAND | SA_NODEFER);  // System V semantics
  if (sigaction(sig, &sa, &old) < 0) return SIG_ERR;
  return old.sa_handler;
}
