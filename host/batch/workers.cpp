#include "batch/workers.h"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <map>
#include <new>
#include <stdexcept>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

namespace uvpress::batch {

namespace {

// Shared between the batch and its workers (an anonymous shared mapping).
struct SharedState {
  std::atomic<size_t> next{0};
  std::atomic<size_t> done{0};
  std::atomic<long> current[kMaxWorkers];  // per worker slot: the task it is on, -1 when none
};
static_assert(std::atomic<size_t>::is_always_lock_free && std::atomic<long>::is_always_lock_free,
              "cross-process counters need lock-free atomics");

std::string signal_name(int sig) {
  const char* d = strsignal(sig);
  return "signal " + std::to_string(sig) + (d ? std::string(" (") + d + ")" : "");
}

}  // namespace

void run_in_workers(size_t total, unsigned jobs, const WorkerSetup& setup, const WorkerDeath& died) {
  void* mem = mmap(nullptr, sizeof(SharedState), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (mem == MAP_FAILED) throw std::runtime_error(std::string("mmap: ") + std::strerror(errno));
  auto* shared = new (mem) SharedState();
  for (auto& c : shared->current) c.store(-1);
  const pid_t batch_pid = getpid();
  std::fflush(nullptr);
  auto spawn = [&](unsigned w) -> pid_t {
    pid_t pid = fork();
    if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if (pid > 0) return pid;
    // Worker: dies with the batch, never returns into the caller's stack.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != batch_pid) _exit(1);
    int status = 0;
    try {
      const WorkerTask run = setup();
      for (;;) {
        size_t k = shared->next.fetch_add(1);
        if (k >= total) break;
        shared->current[w].store(long(k));
        run(k, [&] {
          size_t done = shared->done.fetch_add(1) + 1;
          shared->current[w].store(-1);
          return done;
        });
      }
    } catch (...) {
      status = 1;
    }
    std::fflush(nullptr);
    _exit(status);
  };
  std::map<pid_t, unsigned> workers;
  for (unsigned w = 0; w < jobs; ++w) workers[spawn(w)] = w;
  while (!workers.empty()) {
    int status = 0;
    pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    auto it = workers.find(pid);
    if (it == workers.end()) continue;
    unsigned w = it->second;
    workers.erase(it);
    long k = shared->current[w].exchange(-1);
    if (k >= 0) {
      // The worker died inside a task: fail that task, keep going with the rest.
      std::string why = WIFSIGNALED(status) ? "crashed with " + signal_name(WTERMSIG(status))
                                            : "worker exited with status " + std::to_string(WEXITSTATUS(status));
      died(size_t(k), why, [&] { return shared->done.fetch_add(1) + 1; });
    }
    if (shared->next.load() < total) workers[spawn(w)] = w;
  }
  shared->~SharedState();
  munmap(mem, sizeof(SharedState));
}

}  // namespace uvpress::batch
