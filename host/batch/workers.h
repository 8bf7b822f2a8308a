// batch's worker pool: tasks 0..count-1 run in forked worker processes, `jobs` of them at
// once, each worker taking the next task from a counter they share (an anonymous shared
// mapping). Fork happens before any engine or OpenMP thread exists in the batch process,
// so it is safe; each worker makes its own engine. A worker that dies (a crash, an
// out-of-memory kill) fails only the task it was on; a fresh worker carries on with the
// rest. Workers die with the batch (SIGKILL on parent death).
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace uvpress::batch {

constexpr unsigned kMaxWorkers = 256;

// Runs task `task` in a worker; calls `finished()` once its result is on disk, which
// counts it done (a death after that no longer fails it) and returns how many tasks are
// done in all, for the progress line.
using WorkerTask = std::function<void(size_t task, const std::function<size_t()>& finished)>;
// Runs once in each fresh worker process, before its first task; returns what runs a task.
using WorkerSetup = std::function<WorkerTask()>;
// Runs in the batch process for a task whose worker died on it: `why` says how ("crashed
// with signal 9 (Killed)"); `finished()` as for a task.
using WorkerDeath = std::function<void(size_t task, const std::string& why, const std::function<size_t()>& finished)>;

// Returns once every task ran (or its worker died on it). `jobs` is at most kMaxWorkers.
// Throws std::runtime_error when the shared mapping or a fork fails.
void run_in_workers(size_t count, unsigned jobs, const WorkerSetup& setup, const WorkerDeath& died);

}  // namespace uvpress::batch
