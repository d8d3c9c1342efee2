// Real-time mode of a loop thread (Linux): SCHED_FIFO for the calling thread and the process's
// memory locked, when the process is permitted; otherwise a report that names what failed, and the
// loop carries on with normal scheduling. ROS-free.
//
// What it takes (driver_node's ~realtime_priority, README "Real-time mode"):
//   SCHED_FIFO  pthread_setschedparam(self, SCHED_FIFO, priority): CAP_SYS_NICE, or RLIMIT_RTPRIO
//               (`ulimit -r`, limits.conf `rtprio`) at least the priority; else EPERM.
//   mlockall    mlockall(MCL_CURRENT | MCL_FUTURE): CAP_IPC_LOCK, or RLIMIT_MEMLOCK (`ulimit -l`,
//               limits.conf `memlock`) above the process's size; else ENOMEM (or EPERM). With it, the
//               loop never waits on a page fault: after it, the calling thread's stack is touched
//               (kStackPrefaultBytes) so its pages are resident too.
// Call enter_realtime() on the loop thread itself before its first cycle: the priority is the calling
// thread's, the memory lock the whole process's. Not in the periodic path: report texts allocate.
#pragma once

#include <cstddef>
#include <string>

namespace snake_autonomy::driver {

struct RealtimeReport {
  int requested_priority = 0;  // 0: real-time mode not requested (normal scheduling)
  bool fifo = false;           // the thread runs SCHED_FIFO at requested_priority (checked after the call)
  int fifo_errno = 0;          // why not (EPERM, EINVAL), 0 when it does or was not requested
  bool memory_locked = false;  // mlockall(MCL_CURRENT | MCL_FUTURE) succeeded
  int lock_errno = 0;          // why not (ENOMEM, EPERM, EAGAIN), 0 when locked or not requested

  bool requested() const noexcept { return requested_priority > 0; }
  // Requested, but the thread or the memory did not get it.
  bool degraded() const noexcept { return requested() && (!fifo || !memory_locked); }
  // One line for /diagnostics: "off (normal scheduling)", "SCHED_FIFO priority 50, memory locked", or
  // what the loop runs with after a refusal ("normal scheduling (SCHED_FIFO 50 refused: EPERM), memory locked").
  std::string mode() const;
  // "" unless degraded(): what failed with its errno name and meaning, what the loop does now, and how
  // to grant it.
  std::string warning() const;
};

inline constexpr std::size_t kStackPrefaultBytes = 256 * 1024;

// Applies the mode to the calling thread (priority 1 .. 99; 0 does nothing and reports "off").
// Never throws; allocation-free.
RealtimeReport enter_realtime(int priority) noexcept;

// "EPERM", "ENOMEM", ... for the errors above; "errno N" otherwise (a static text).
const char* errno_name(int error) noexcept;

}  // namespace snake_autonomy::driver
