function datagrams = vlab_split_datagrams(bytes)
% VLAB_SPLIT_DATAGRAMS  Whole datagrams read back to back (a uint8 row) as a cell array
%   of uint8 rows, one datagram each. A float64 datagram is 8 * (7 + length) bytes, its
%   length being value 7 of its header; a describe reply (JSON, first byte '{') is never
%   followed by another datagram in vlab_connect's order, so it takes the rest. Bytes that
%   do not make a whole datagram are handed on as they are, for the caller to skip.
datagrams = {};
while numel(bytes) >= 56 && bytes(1) ~= uint8('{')
  n_bytes = 8 * (7 + typecast(bytes(49:56), 'double'));
  if ~(n_bytes >= 56 && n_bytes <= numel(bytes) && n_bytes == round(n_bytes))
    break;
  end
  datagrams{end + 1} = bytes(1:n_bytes);
  bytes = bytes(n_bytes + 1:end);
end
if ~isempty(bytes)
  datagrams{end + 1} = bytes;
end
end
