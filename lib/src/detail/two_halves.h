// Work over independent rows, split between this thread and one more: the start-up tables (a
// locus, the simulator's rates) compute Planck's law at every wavelength for thousands of
// temperatures while an element starts.
#pragma once

#include <exception>
#include <system_error>
#include <thread>

namespace pyrocam::detail {

// Calls rows(from, to) on [0, n): the second half on another thread where n is at least
// worth_a_thread and the machine has two cores, else all here. Each row must be computed alone,
// so the values do not depend on the split. An exception from either half is rethrown here.
template <class Index, class Rows>
void in_two_halves(Index n, Index worth_a_thread, const Rows& rows) {
  if (n < worth_a_thread || std::thread::hardware_concurrency() < 2) {
    rows(Index{0}, n);
    return;
  }
  const Index half = n / 2;
  std::exception_ptr failed;
  std::thread second;
  try {
    second = std::thread([&] {
      try {
        rows(half, n);
      } catch (...) {
        failed = std::current_exception();
      }
    });
  } catch (const std::system_error&) {  // no thread to be had: all here
    rows(Index{0}, n);
    return;
  }
  try {
    rows(Index{0}, half);
  } catch (...) {
    second.join();
    throw;
  }
  second.join();
  if (failed) std::rethrow_exception(failed);
}

}  // namespace pyrocam::detail
