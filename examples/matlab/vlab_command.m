function vlab_command(link, seq, mode, values)
% VLAB_COMMAND  Send an arm command that answers the state numbered seq.
%   mode: 0 hold, 1 position (values in rad), 2 velocity (rad/s), 3 torque (N m);
%   values: one per joint (link.joints of them; send zeros with a hold).
%   [magic version kind=1 type=2 seq time length=1+n mode values]; time is the sender's
%   clock, informative only, so 0 here. A command the arm refuses (a limit, NaN) sets
%   the refused status bit in the next state; the previous command stays in force.
values = double(values(:).');
if numel(values) ~= link.joints
  error('vlab_command: %d values for an arm of %d joints', numel(values), link.joints);
end
msg = [1447838018, 2, 1, 2, seq, 0, 1 + link.joints, mode, values];
write(link.socket, typecast(msg, 'uint8'), 'uint8', link.host, link.port);
end
