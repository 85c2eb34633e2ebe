#pragma once
// A log fed to a reader through a real pipe, as `cat LOG | shutterlab flight /dev/stdin` feeds it:
// readable once, of no known size, not seekable, written by another thread as the reader reads.

#include "sim/check.h"
#include "sim/logs/flight_log_io.h"

#include <csignal>
#include <pthread.h>
#include <string>
#include <thread>
#include <unistd.h>

namespace shutterlab::test {

// What read(path) gives when path names the reading end of a pipe that carries bytes.
template <typename Read>
auto ReadThroughPipe(const std::string& bytes, Read read) {
  int fds[2];
  SHUTTERLAB_CHECK(::pipe(fds) == 0) << "pipe";
  std::thread writer([&bytes, fd = fds[1]] {
    // A reader that stops early closes the pipe: the writer's write() then fails with EPIPE
    // instead of raising SIGPIPE, which is sent to the writing thread and blocked in it alone.
    sigset_t pipe_signal;
    sigemptyset(&pipe_signal);
    sigaddset(&pipe_signal, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_signal, nullptr);
    for (size_t done = 0; done < bytes.size();) {
      const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
      if (n <= 0) break;
      done += static_cast<size_t>(n);
    }
    ::close(fd);
  });
  struct Cleanup {
    std::thread& writer;
    int read_fd;
    ~Cleanup() {
      ::close(read_fd);  // before the join: a writer still writing then stops
      writer.join();
    }
  } cleanup{writer, fds[0]};
  return read("/proc/self/fd/" + std::to_string(fds[0]));
}

// What ReadFlightLog makes of bytes that come down a pipe.
inline FlightLog ReadFromPipe(const std::string& bytes, const FlightLogReadOptions& options = {}) {
  return ReadThroughPipe(
      bytes, [&options](const std::string& path) { return ReadFlightLog(path, options); });
}

}  // namespace shutterlab::test
