#include "server/node/slave_sample.hpp"

#include "common/control/slave_port.hpp"

namespace teleop::server {

void slave_sample(const ServerCycle& cycle, SlaveSample& s) {
  copy_tip_state(cycle.output(), s);
  s.seq = cycle.steps();
  s.command_seq = cycle.have_command() ? cycle.command().seq : 0;
  s.command_send_time_s = cycle.have_command() ? cycle.command().send_time_s : 0.0;
  s.valid = true;
  passivity::apply_port_report(cycle.port().report(), s);
  if (!cycle.port_active()) s.passivity_session = 0;
  s.model = cycle.local_model();
}

}  // namespace teleop::server
