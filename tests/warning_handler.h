// A scope's MuJoCo warning handler, for the tests that count warnings instead of failing on them.
#ifndef MJTETHER_TESTS_WARNING_HANDLER_H_
#define MJTETHER_TESTS_WARNING_HANDLER_H_

#include <mujoco/mujoco.h>

namespace mjtether::testing {

// Sets mju_user_warning for a scope and puts the previous handler back on every way out of it,
// an ASSERT's early return included, so that a test's counter never stays the handler of the
// tests after it.
class WarningHandler {
 public:
  explicit WarningHandler(void (*handler)(const char*)) : previous_(mju_user_warning) {
    mju_user_warning = handler;
  }
  ~WarningHandler() { mju_user_warning = previous_; }
  WarningHandler(const WarningHandler&) = delete;
  WarningHandler& operator=(const WarningHandler&) = delete;

 private:
  void (*previous_)(const char*);
};

}  // namespace mjtether::testing

#endif  // MJTETHER_TESTS_WARNING_HANDLER_H_
