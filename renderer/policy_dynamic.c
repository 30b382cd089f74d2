/* The dynamic policy: rays queued at queue points (stub until built). */
#include "renderer/policy.h"
#include "sim/err.h"

void policy_dynamic_run(const struct policy_env *env, const struct policy_params *p) {
  (void)env;
  (void)p;
  CHECK(!"dynamic policy not built yet");
}
