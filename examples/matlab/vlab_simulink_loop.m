function vlab_simulink_loop(host, port, n_states)
% VLAB_SIMULINK_LOOP  The Simulink model of docs/protocol.md ("Simulink") as a loop, to
%   try vlab_simulink_session without Simulink: each step, like the DSP System
%   Toolbox's UDP Receive, takes at most one datagram and pads it to 29 values; the
%   block's request and command go out when enabled. The controller holds the arm
%   (velocity mode, zero velocities). Stops after n_states states.
%     vlab_simulink_loop('127.0.0.1', 50010, 100)
%   Octave on Linux only: a read of NumBytesAvailable bytes is exactly one datagram
%   there (vlab_receive.m).
pkg('load', 'instrument-control');
u = udpport('Timeout', 1);
answered = 0;
started = tic;
while answered < n_states
  if toc(started) > 10
    error('vlab_simulink_loop: %d states in 10 s, expected %d', answered, n_states);
  end
  % UDP Receive: one datagram per sample, 29 values, and how many were received
  rx = zeros(29, 1);
  rx_length = 0;
  if u.NumBytesAvailable > 0
    v = typecast(uint8(read(u, u.NumBytesAvailable, 'uint8')), 'double');
    rx_length = min(numel(v), 29);
    rx(1:rx_length) = v(1:rx_length);
  else
    pause(0.0002);
  end
  [request, send_request, new_state, state] = vlab_simulink_session(rx, rx_length);
  if send_request
    write(u, typecast(request.', 'uint8'), 'uint8', host, port);
  end
  if new_state
    seq = state(5);
    command = [1447838018, 2, 1, 2, seq, 0, 8, 2, zeros(1, 7)];
    write(u, typecast(command, 'uint8'), 'uint8', host, port);
    answered = answered + 1;
  end
end
fprintf('vlab_simulink_loop: answered %d states, the last seq %d\n', answered, seq);
end
