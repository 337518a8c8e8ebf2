#include "resolvers/rigid_body/ode_support.hpp"

#include <atomic>
#include <cstdarg>
#include <cstdio>
#include <mutex>

namespace alloy::rigid {

namespace {

std::string format(int num, const char* msg, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof text, msg, ap);
  return "ODE error " + std::to_string(num) + ": " + text;
}

// dError and dDebug call these and abort() if they return: they must not
// return. Throwing unwinds through ODE's frames to the stage that called ODE.
void throw_error(int num, const char* msg, va_list ap) {
  throw OdeError(format(num, msg, ap));
}

std::atomic<std::uint64_t> message_count{0};
std::mutex last_message_mutex;
std::string last_message;

void keep_message(int num, const char* msg, va_list ap) {
  ++message_count;
  std::string text = format(num, msg, ap);
  std::lock_guard lock(last_message_mutex);
  last_message = std::move(text);
}

}  // namespace

void ensure_ode() {
  static std::once_flag once;
  std::call_once(once, [] {
    dInitODE2(0);
    dSetErrorHandler(&throw_error);
    dSetDebugHandler(&throw_error);
    dSetMessageHandler(&keep_message);
  });
  // dInitODE2 allocated the initialising thread's data; other threads need theirs.
  thread_local bool thread_ready = false;
  if (!thread_ready) {
    dAllocateODEDataForThread(dAllocateMaskAll);
    thread_ready = true;
  }
}

std::uint64_t ode_message_count() {
  return message_count.load();
}

std::string last_ode_message() {
  std::lock_guard lock(last_message_mutex);
  return last_message;
}

}  // namespace alloy::rigid
