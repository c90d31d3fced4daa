function vlab_request(link, type, arg)
% VLAB_REQUEST  Send a describe (type 3, arg 0) or subscribe request (type 4, arg 1
%   subscribe or renew, 0 unsubscribe) to the arm, with link.cookie (0 before the
%   device gave one): nine float64 values, 72 bytes.
%   [magic version kind type seq time length cookie arg], little-endian like every
%   float64 of the protocol; typecast uses the host's byte order, which is little-endian
%   on every machine MATLAB and Octave run on (x86-64, Apple silicon).
msg = [1447838018, 2, 1, type, 0, 0, 2, link.cookie, arg];
write(link.socket, typecast(msg, 'uint8'), 'uint8', link.host, link.port);
end
