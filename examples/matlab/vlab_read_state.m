function state = vlab_read_state(link)
% VLAB_READ_STATE  The newest arm state waiting on the socket, or else the next one to
%   come (in lockstep: the state of the period the lab waits on).
%   Skips describe replies (JSON, first byte '{') and session replies (type 5, 72 bytes:
%   the answers to the subscription and its renewals). Fields, rows with one value per joint:
%     seq     the period the state closes: answer it with vlab_command(link, seq, ...)
%     time    simulated time (s)
%     status  sum of status bits: 1 holding, 2 refused, 4 saturated, 8 at_limit,
%             16 watchdog, 32 not_owner
%     q, qd, tau   joint positions (rad), velocities (rad/s), applied torques (N m)
%   Raises an error when no state comes within link.timeout_s seconds, when the arm
%   refuses the subscription, or when it speaks another protocol version.
state = [];
started = tic;
while isempty(state)
  remaining = link.timeout_s - toc(started);
  if remaining <= 0
    error('vlab_read_state: no state from %s:%d within %g s', link.host, link.port, link.timeout_s);
  end
  datagrams = vlab_receive(link, remaining);
  for i = 1:numel(datagrams)
    bytes = datagrams{i};
    if numel(bytes) < 56 || bytes(1) == uint8('{') || mod(numel(bytes), 8) ~= 0
      continue;                                % a describe reply, or not ours
    end
    v = typecast(bytes, 'double');             % [magic version kind type seq time length payload]
    if v(1) ~= 1447838018
      continue;
    end
    if v(2) ~= 2
      error('vlab_read_state: the device speaks protocol %g, this code 2', v(2));
    end
    if numel(v) == 9 && v(4) == 5 && v(9) == 2   % session reply [... 5 0 0 2 cookie result]
      error('vlab_read_state: %s:%d refused the subscription: it has all the subscribers it takes', ...
            link.host, link.port);
    end
    if v(3) ~= 1 || v(4) ~= 1 || v(7) ~= numel(v) - 7 || v(7) ~= 1 + 3 * link.joints
      continue;                                % any other session reply, not an arm state
    end
    n = link.joints;
    state = struct('seq', v(5), 'time', v(6), 'status', v(8), 'q', v(9:8 + n), ...
                   'qd', v(9 + n:8 + 2 * n), 'tau', v(9 + 2 * n:8 + 3 * n));
  end
end
end
