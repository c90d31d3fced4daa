function [request, send_request, new_state, state] = vlab_simulink_session(rx, rx_length)
%#codegen
% VLAB_SIMULINK_SESSION  The code of a MATLAB Function block that keeps a Simulink model
%   subscribed to a vlab arm of 7 joints (protocol 2) and picks its states out of what
%   the DSP System Toolbox's UDP Receive block outputs (docs/protocol.md, "Simulink").
%   Inputs, one sample of UDP Receive (Data type double, Maximum length 29, Output
%   variable-size signal off):
%     rx         29 values: the datagram received in this sample, then padding
%     rx_length  the number of values received in this sample (0: none)
%   Outputs:
%     request       a subscribe request, 9 values, for a UDP Send block in an Enabled
%     send_request  Subsystem, and its enable: the first request (cookie 0) brings the
%                   challenge, the next one (with its cookie) subscribes, and then one
%                   renews the subscription every RENEW_STEPS steps
%     new_state     true in the sample that brought a new state: the enable of the UDP
%                   Send of the command [1447838018 2 1 2 seq 0 8 mode value_1..value_7]
%     state         the newest state, 29 values, held between states: 5 seq (answer it),
%                   6 time (s), 8 status, 9..15 q (rad), 16..22 qd (rad/s), 23..29 tau
%                   (N m); zeros before the first
%   Session replies (element 4 == 5) end here: a challenge (element 9 == 0) brings the
%   cookie (element 8), and the request that follows carries it.
MAGIC = 1447838018;
JOINTS = 7;
STATE_VALUES = 7 + 1 + 3 * JOINTS;   % header, status, q, qd, tau: 29
RENEW_STEPS = 500;            % at a 2 ms step: about once a second

persistent cookie steps_to_request last_state
if isempty(cookie)
  cookie = 0;                 % none yet
  steps_to_request = 0;       % the first request goes out in the first step
  last_state = zeros(STATE_VALUES, 1);
end

new_state = false;
if rx_length >= 7 && rx(1) == MAGIC && rx(2) == 2
  if rx(4) == 5 && rx_length == 9                       % session reply
    if rx(9) == 0 && rx(8) ~= cookie                    % challenge: subscribe with it, now
      cookie = rx(8);
      steps_to_request = 0;
    end
  elseif rx(4) == 1 && rx_length == STATE_VALUES       % arm state
    new_state = true;
    last_state = rx(1:STATE_VALUES);
    last_state = last_state(:);
  end
end
state = last_state;

% a request now and then: it retries the handshake until the states come, and once
% subscribed it renews (commands renew too, so this matters before the first one, or
% when the lab restarted and the cookie changed: the renewal then brings a challenge)
send_request = steps_to_request <= 0;
if send_request
  steps_to_request = RENEW_STEPS;
end
steps_to_request = steps_to_request - 1;
request = [MAGIC; 2; 1; 4; 0; 0; 2; cookie; 1];
end
