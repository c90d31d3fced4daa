function vlab_arm_hold(host, port, n_states)
% VLAB_ARM_HOLD  Hold the arm where it starts, from MATLAB or Octave, over vlab's UDP
%   protocol 2: connect, answer n_states states, leave.
%     vlab_arm_hold                             % 127.0.0.1:50010, 1000 states
%     vlab_arm_hold('127.0.0.1', 50010, 500)
%   Start the lab first, e.g.  build/vlab serve scenes/pa10_serve  (lockstep: it waits
%   for each command). Octave needs the instrument-control package (Debian:
%   octave-instrument-control); MATLAB R2020b+ the Instrument Control Toolbox.
%
%   Each state is answered with a velocity command that pulls the arm back to the pose
%   of the first state, qd_cmd = K (q_hold - q) (rad/s), carrying the state's seq, so in
%   lockstep the lab simulates the next period as soon as it has the command. Prints one
%   line: the states answered, the seqs skipped and the states on watchdog hold (both 0
%   in lockstep; in realtime they count the periods we were too slow for), the largest
%   joint deviation. Raises an error (Octave and MATLAB -batch exit non-zero) when the
%   arm does not answer, refuses a command, or takes commands from another client.
if nargin < 1, host = '127.0.0.1'; end
if nargin < 2, port = 50010; end
if nargin < 3, n_states = 1000; end
gain = 10;                    % K, 1/s
renew_every_s = 0.5;          % simulated time between subscription renewals

link = vlab_connect(host, port);
fprintf('vlab_arm_hold: connected to arm ''%s'' (%d joints) at %s:%d\n', ...
        link.name, link.joints, host, port);

state = vlab_read_state(link);
q_hold = state.q;
first_seq = state.seq;
last_seq = state.seq - 1;
skipped = 0;
watchdog = 0;
max_deviation = 0;
next_renew_s = state.time + renew_every_s;
for k = 1:n_states
  if k > 1
    state = vlab_read_state(link);
  end
  % refused (2) or not_owner (32): our commands do not drive the arm
  if bitand(state.status, 2 + 32)
    error('vlab_arm_hold: state %d has status %d (2 refused, 32 not owner)', state.seq, state.status);
  end
  % watchdog (16): in realtime we were late for more than watchdog_periods periods
  watchdog = watchdog + (bitand(state.status, 16) ~= 0);
  skipped = skipped + (state.seq - last_seq - 1);   % realtime: states we were too slow for
  last_seq = state.seq;
  max_deviation = max(max_deviation, max(abs(q_hold - state.q)));

  vlab_command(link, state.seq, 2, gain * (q_hold - state.q));

  % commands keep the subscription alive already; a client that only reads (a logger)
  % must renew it, at least every 10 s: shown here. The session reply that answers
  % it (type 5) is skipped by vlab_read_state.
  if state.time >= next_renew_s
    vlab_request(link, 4, 1);
    next_renew_s = state.time + renew_every_s;
  end
end

vlab_request(link, 4, 0);     % unsubscribe: the arm is released at once
fprintf(['vlab_arm_hold: answered %d states (seq %d to %d), skipped %d, on watchdog hold %d, ' ...
         'max deviation %.3g rad\n'], n_states, first_seq, last_seq, skipped, watchdog, max_deviation);
end
