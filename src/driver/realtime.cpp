#include "snake_autonomy/driver/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>

namespace snake_autonomy::driver {

namespace {

// Touches kStackPrefaultBytes of the calling thread's stack (resident and, after mlockall, locked).
__attribute__((noinline)) void prefault_stack() noexcept {
  volatile unsigned char stack[kStackPrefaultBytes];
  for (std::size_t i = 0; i < sizeof stack; i += 4096) stack[i] = 0;
}

std::string describe(int error) { return std::string(errno_name(error)) + ": " + std::strerror(error); }

}  // namespace

const char* errno_name(int error) noexcept {
  switch (error) {
    case EPERM: return "EPERM";
    case ENOMEM: return "ENOMEM";
    case EINVAL: return "EINVAL";
    case EAGAIN: return "EAGAIN";
    case ESRCH: return "ESRCH";
    case ENOTSUP: return "ENOTSUP";
    default: return "errno";
  }
}

RealtimeReport enter_realtime(int priority) noexcept {
  RealtimeReport r;
  r.requested_priority = priority > 0 ? priority : 0;
  if (!r.requested()) return r;
  sched_param p{};
  p.sched_priority = priority;
  r.fifo_errno = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
  if (r.fifo_errno == 0) {  // check what the thread runs with now
    int policy = 0;
    sched_param now{};
    r.fifo = pthread_getschedparam(pthread_self(), &policy, &now) == 0 && policy == SCHED_FIFO &&
             now.sched_priority == priority;
  }
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    r.memory_locked = true;
  } else {
    r.lock_errno = errno;
  }
  prefault_stack();
  return r;
}

std::string RealtimeReport::mode() const {
  if (!requested()) return "off (normal scheduling)";
  const std::string p = std::to_string(requested_priority);
  std::string out = fifo ? "SCHED_FIFO priority " + p
                         : "normal scheduling (SCHED_FIFO " + p + " refused: " + errno_name(fifo_errno) + ")";
  out += memory_locked ? ", memory locked"
                       : std::string(", memory not locked (mlockall refused: ") + errno_name(lock_errno) + ")";
  return out;
}

std::string RealtimeReport::warning() const {
  if (!degraded()) return "";
  std::string out = "realtime_priority " + std::to_string(requested_priority) + ":";
  if (!fifo) {
    out += " SCHED_FIFO refused (" + (fifo_errno ? describe(fifo_errno) : std::string("not in effect after the call")) +
           "): the loop thread runs with normal scheduling;";
  }
  if (!memory_locked) {
    out += " mlockall(MCL_CURRENT|MCL_FUTURE) refused (" + describe(lock_errno) +
           "): memory is not locked, a page fault can stall a cycle;";
  }
  out +=
      " the driver carries on. To grant it: run with CAP_SYS_NICE and CAP_IPC_LOCK (setcap "
      "cap_sys_nice,cap_ipc_lock+ep on driver_node), or raise the limits for the user (limits.conf: "
      "'<user> - rtprio 99' and '<user> - memlock unlimited'; ulimit -r / ulimit -l)";
  return out;
}

}  // namespace snake_autonomy::driver
