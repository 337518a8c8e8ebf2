#include "resolvers/rigid_body/ode_support.hpp"

#include <mutex>

namespace alloy::rigid {

void ensure_ode() {
  static std::once_flag once;
  std::call_once(once, [] { dInitODE2(0); });
  // dInitODE2 allocated the initialising thread's data; other threads need theirs.
  thread_local bool thread_ready = false;
  if (!thread_ready) {
    dAllocateODEDataForThread(dAllocateMaskAll);
    thread_ready = true;
  }
}

}  // namespace alloy::rigid
