// driver::enter_realtime: SCHED_FIFO and locked memory when permitted, a report naming what was refused
// otherwise. Each case runs in a forked child: the mode (a thread priority, the process's memory
// lock) and the dropped rights must not leak into the other tests.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <functional>
#include <string>

#include "snake_autonomy/driver/realtime.hpp"

using snake_autonomy::driver::enter_realtime;
using snake_autonomy::driver::RealtimeReport;

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Runs enter_realtime(priority) in a child after `prepare` (which may drop rights); its report.
RealtimeReport in_child(int priority, const std::function<bool()>& prepare) {
  int fds[2];
  EXPECT_EQ(pipe(fds), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    RealtimeReport r;
    r.requested_priority = -1;  // the child could not prepare
    if (prepare()) r = enter_realtime(priority);
    const ssize_t written = write(fds[1], &r, sizeof r);  // plain data: ints and bools
    _exit(written == static_cast<ssize_t>(sizeof r) ? 0 : 1);
  }
  close(fds[1]);
  RealtimeReport r;
  EXPECT_EQ(read(fds[0], &r, sizeof r), static_cast<ssize_t>(sizeof r));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  return r;
}

// Whether this process may have SCHED_FIFO 10 and lock all its memory (root or generous limits).
bool permitted() {
  if (geteuid() == 0) return true;
  rlimit rt{}, lock{};
  getrlimit(RLIMIT_RTPRIO, &rt);
  getrlimit(RLIMIT_MEMLOCK, &lock);
  return (rt.rlim_cur == RLIM_INFINITY || rt.rlim_cur >= 10) && lock.rlim_cur == RLIM_INFINITY;
}

}  // namespace

TEST(Realtime, OffByDefault) {
  const RealtimeReport r = enter_realtime(0);
  EXPECT_FALSE(r.requested());
  EXPECT_FALSE(r.degraded());
  EXPECT_EQ(r.mode(), "off (normal scheduling)");
  EXPECT_EQ(r.warning(), "");
}

TEST(Realtime, SchedFifoAndLockedMemoryWhenPermitted) {
  if (!permitted()) GTEST_SKIP() << "neither root nor rtprio/memlock limits high enough here";
  const RealtimeReport r = in_child(10, [] { return true; });
  EXPECT_TRUE(r.fifo);
  EXPECT_TRUE(r.memory_locked);
  EXPECT_FALSE(r.degraded());
  EXPECT_EQ(r.mode(), "SCHED_FIFO priority 10, memory locked");
  EXPECT_EQ(r.warning(), "");
}

TEST(Realtime, RefusedItSaysWhatFailedAndCarriesOn) {
  // No rights: RLIMIT_RTPRIO 0, RLIMIT_MEMLOCK 64 KiB, and (as root) an unprivileged user: no capabilities.
  const RealtimeReport r = in_child(50, [] {
    const rlimit no_rt{0, 0}, small_lock{64 * 1024, 64 * 1024};
    if (setrlimit(RLIMIT_RTPRIO, &no_rt) != 0 || setrlimit(RLIMIT_MEMLOCK, &small_lock) != 0) return false;
    return geteuid() != 0 || (setgid(65534) == 0 && setuid(65534) == 0);
  });
  ASSERT_EQ(r.requested_priority, 50) << "the child could not drop its rights";
  EXPECT_FALSE(r.fifo);
  EXPECT_EQ(r.fifo_errno, EPERM);
  EXPECT_FALSE(r.memory_locked);
  EXPECT_TRUE(r.lock_errno == ENOMEM || r.lock_errno == EPERM) << r.lock_errno;
  EXPECT_TRUE(r.degraded());
  EXPECT_TRUE(contains(r.mode(), "normal scheduling (SCHED_FIFO 50 refused: EPERM)")) << r.mode();
  const std::string w = r.warning();
  EXPECT_TRUE(contains(w,
                       "realtime_priority 50: SCHED_FIFO refused (EPERM: Operation not permitted): the loop "
                       "thread runs with normal scheduling"))
      << w;
  EXPECT_TRUE(contains(w, "mlockall(MCL_CURRENT|MCL_FUTURE) refused")) << w;
  EXPECT_TRUE(contains(w, "the driver carries on")) << w;
  EXPECT_TRUE(contains(w, "cap_sys_nice,cap_ipc_lock")) << w;
}
