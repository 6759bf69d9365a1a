// Running a file reader on a thread with a large stack (readers that recurse once per nesting
// level of the file: Coin3D, Assimp).
#pragma once

#include <pthread.h>

#include <cstddef>
#include <cstring>
#include <exception>
#include <string>

#include "kccd/modelling/part.hpp"

namespace kccd::modelling::detail {

/// Stack size of the reader thread: far more than the deepest file accepted needs (well under
/// 1 KiB of stack per nesting level).
inline constexpr std::size_t kReaderStackBytes = 256u << 20;

/// Runs `f` on a thread with a kReaderStackBytes stack; its exception is rethrown here.
template <class F>
void onLargeStack(F&& f) {
  struct Job {
    F* f;
    std::exception_ptr error;
  } job{&f, nullptr};
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, kReaderStackBytes);
  pthread_t thread;
  const int created = pthread_create(
      &thread, &attr,
      [](void* data) -> void* {
        auto* j = static_cast<Job*>(data);
        try {
          (*j->f)();
        } catch (...) {
          j->error = std::current_exception();
        }
        return nullptr;
      },
      &job);
  pthread_attr_destroy(&attr);
  if (created != 0) throw PartError("cannot start a reader thread (" + std::string(std::strerror(created)) + ")");
  pthread_join(thread, nullptr);
  if (job.error) std::rethrow_exception(job.error);
}

}  // namespace kccd::modelling::detail
