function datagrams = vlab_receive(link, timeout_s)
% VLAB_RECEIVE  Every datagram waiting on link.socket, waiting up to timeout_s seconds
%   for the first: a cell array of uint8 rows, one datagram each, oldest first; {} when
%   nothing came in time.
%
%   This is the one place where MATLAB and Octave differ:
%   - MATLAB (R2020b+, Instrument Control Toolbox): the socket is udpport("datagram");
%     read(u, count, 'uint8') returns count datagrams as structs whose .Data holds the
%     bytes (as doubles) and blocks up to u.Timeout for them.
%   - Octave (instrument-control 0.8.0, Debian 12's octave-instrument-control): udpport
%     has no datagram mode; read(u, count, 'uint8') counts bytes, waits until it has
%     count of them (across datagrams), and cuts off the rest of a datagram that is
%     longer than asked for. So wait until NumBytesAvailable > 0, then read exactly
%     NumBytesAvailable bytes: on Linux that is the size of the next datagram; on
%     Windows and macOS it is every byte waiting, whole datagrams back to back, which
%     vlab_split_datagrams separates by their length field.

if exist('OCTAVE_VERSION', 'builtin')
  u = link.socket;
  started = tic;
  while u.NumBytesAvailable == 0
    if toc(started) > timeout_s
      datagrams = {};
      return;
    end
    pause(0.0002);
  end
  datagrams = {};
  while u.NumBytesAvailable > 0
    bytes = read(u, u.NumBytesAvailable, 'uint8');
    datagrams = [datagrams, vlab_split_datagrams(uint8(bytes(:).'))];
  end
else
  u = link.socket;
  u.Timeout = timeout_s;
  d = read(u, 1, 'uint8');                     % [] (and a warning) after the timeout
  if u.NumDatagramsAvailable > 0
    d = [d, read(u, u.NumDatagramsAvailable, 'uint8')];
  end
  datagrams = cell(1, numel(d));
  for i = 1:numel(d)
    datagrams{i} = uint8(d(i).Data(:).');
  end
end
end
