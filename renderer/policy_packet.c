/* The packet policy: 8x8 packets tiled over the image (stub until built). */
#include "renderer/policy.h"
#include "sim/err.h"

void policy_packet_run(const struct policy_env *env, const struct policy_params *p) {
  (void)env;
  (void)p;
  CHECK(!"packet policy not built yet");
}
