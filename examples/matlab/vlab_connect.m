function link = vlab_connect(host, port, timeout_s)
% VLAB_CONNECT  Open a UDP socket and subscribe to the vlab arm at host:port (protocol 2).
%   link = vlab_connect('127.0.0.1', 50010) returns the struct that vlab_read_state,
%   vlab_command and vlab_request take:
%     socket     the udpport object (MATLAB: datagram mode; Octave: instrument-control)
%     host, port the arm's address and port
%     cookie     the cookie the arm gave this socket's address and port
%     name       the arm's name; joints: its number of joints, n
%     describe   the decoded describe reply (limits, joint names, rates, ...)
%     timeout_s  how long a read waits (1 s unless given)
%   The handshake of "Sessions" in docs/protocol.md: a subscribe request with cookie 0
%   is answered with a challenge that carries the cookie; the describe request with the
%   cookie brings the JSON describe reply; the subscribe request with the cookie starts
%   the states (the first one read with vlab_read_state). Nothing streams before the
%   subscription, so no state is missed while the JSON is read. Raises an error when the
%   arm does not answer or is not a protocol-2 arm.
if nargin < 3
  timeout_s = 1.0;
end
if exist('OCTAVE_VERSION', 'builtin')
  pkg('load', 'instrument-control');
  socket = udpport('Timeout', timeout_s);      % any free local port
else
  socket = udpport('datagram', 'Timeout', timeout_s);
end
link = struct('socket', socket, 'host', host, 'port', port, 'cookie', 0, 'name', '', ...
              'joints', 0, 'describe', [], 'timeout_s', timeout_s);

% cookie: a challenge comes back, whatever we asked
vlab_request(link, 4, 1);
[link.cookie, result] = session_reply(link);
if result ~= 0
  error('vlab_connect: %s:%d answered result %g, expected a challenge (0)', host, port, result);
end

% describe: the JSON reply
vlab_request(link, 3, 0);
bytes = next_datagram(link, 'describe reply');
if bytes(1) ~= uint8('{')
  error('vlab_connect: %s:%d sent no describe reply', host, port);
end
link.describe = jsondecode(char(bytes));
if link.describe.protocol ~= 2 || ~strcmp(link.describe.kind, 'arm')
  error('vlab_connect: %s:%d is a %s of protocol %g, not an arm of protocol 2', ...
        host, port, link.describe.kind, link.describe.protocol);
end
link.name = link.describe.name;
link.joints = numel(link.describe.joints);

% subscribe: the session reply (result 1) and the states follow, possibly in the same
% read, so they are left to vlab_read_state, which skips the one and returns the other
vlab_request(link, 4, 1);
end

function [cookie, result] = session_reply(link)
% the next session reply (type 5): [magic version kind 5 0 0 2 cookie result]
bytes = next_datagram(link, 'session reply');
v = [];
if numel(bytes) == 72
  v = typecast(bytes, 'double');
end
if numel(v) ~= 9 || v(1) ~= 1447838018 || v(4) ~= 5
  error('vlab_connect: %s:%d sent no session reply (a protocol-2 arm answers 72 bytes)', link.host, link.port);
end
cookie = v(8);
result = v(9);
end

function bytes = next_datagram(link, what)
% the first datagram that comes, or an error naming what we waited for
datagrams = vlab_receive(link, link.timeout_s);
if isempty(datagrams)
  error('vlab_connect: no %s from %s:%d within %g s (is vlab serve running there?)', ...
        what, link.host, link.port, link.timeout_s);
end
bytes = datagrams{1};
end
