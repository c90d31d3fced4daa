#!/usr/bin/env bash
# The run log's binary formats read by other programs, bit for bit against log.csv:
#   octave: Octave's `load` reads log.mat (one struct per column group: data, names,
#           units as char rows); every value's bits (num2hex) equal log.csv's value parsed by Python.
#   h5py:   python3-h5py reads log.h5 (/log, attributes columns and units); every
#           value's bits equal log.csv's.
# One run of scenes/pa10_reach (3 s, 1501 rows: more than one HDF5 chunk) writes all
# three formats. Without the tool the test is skipped (exit 77), the reason printed.
#   log_formats_tools_test.sh VLAB OUT_DIR octave|h5py
set -u
vlab="$1"; out="$2"; tool="$3"
skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAIL: $*"; exit 1; }
# h5py from Debian's python3 where the python3 first on PATH lacks it
python=python3
[ "$tool" = h5py ] && ! python3 -c 'import h5py' 2>/dev/null && [ -x /usr/bin/python3 ] && python=/usr/bin/python3
case "$tool" in
  octave) command -v octave >/dev/null || skip "no octave (./test.sh installs it; Debian: octave)" ;;
  h5py) "$python" -c 'import h5py' 2>/dev/null || skip "no h5py (./test.sh installs it; Debian: python3-h5py)" ;;
  *) fail "unknown tool '$tool'" ;;
esac
rm -rf "$out"; mkdir -p "$out"
"$vlab" run scenes/pa10_reach -q --duration 3 --out "$out/run" \
  --set 'outputs.log={format: [csv, hdf5, mat]}' >"$out/run.txt" 2>&1 || fail "vlab run: $(cat "$out/run.txt")"

# log.csv's values as bits: one line "COLUMN HEX" per value, row by row
python3 - "$out/run/log.csv" >"$out/csv_bits.txt" <<'PY' || fail "reading log.csv"
import struct, sys
lines = open(sys.argv[1]).read().splitlines()
names = lines[0].split(',')
for line in lines[1:]:
    for name, text in zip(names, line.split(',')):
        print(name, struct.pack('>d', float(text)).hex())
PY

if [ "$tool" = octave ]; then
  # each group's struct: for every column its name, then its values' bits, row by row
  timeout 120 octave --norc --no-gui --quiet --eval "
    s = load('$out/run/log.mat');
    f = fopen('$out/mat_columns.txt', 'w');
    for v = fieldnames(s)'
      g = s.(v{1});
      assert(isstruct(g) && isfield(g, 'data') && isfield(g, 'names') && isfield(g, 'units'));
      names = cellstr(g.names);
      assert(ischar(g.names) && ischar(g.units) && numel(names) == columns(g.data) && rows(g.units) == columns(g.data));
      for c = 1:columns(g.data)
        fprintf(f, '%s %s\n', names{c}, strjoin(cellstr(num2hex(g.data(:, c)))', ' '));
      end
    end
    fclose(f);" >"$out/octave.txt" 2>&1 || fail "octave: $(cat "$out/octave.txt")"
  python3 - "$out/csv_bits.txt" "$out/mat_columns.txt" <<'PY' || exit 1
import sys
csv = {}
for line in open(sys.argv[1]):
    name, bits = line.split()
    csv.setdefault(name, []).append(bits)
mat = {}
for line in open(sys.argv[2]):
    name, *bits = line.split()
    mat[name] = bits
if set(mat) != set(csv): sys.exit("FAIL: log.mat's columns differ from log.csv's: %s" % sorted(set(mat) ^ set(csv)))
for name in csv:
    if mat[name] != csv[name]: sys.exit("FAIL: column %s differs between log.mat and log.csv" % name)
print("octave: %d columns x %d rows of log.mat equal log.csv bit for bit" % (len(csv), len(csv['time'])))
PY
else
  "$python" - "$out/csv_bits.txt" "$out/run/log.h5" <<'PY' || exit 1
import struct, sys, h5py
csv = {}
for line in open(sys.argv[1]):
    name, bits = line.split()
    csv.setdefault(name, []).append(bits)
with h5py.File(sys.argv[2], 'r') as f:
    log = f['log']
    names = [n.decode() if isinstance(n, bytes) else n for n in log.attrs['columns']]
    units = list(log.attrs['units'])
    data = log[:]
if len(units) != len(names): sys.exit("FAIL: %d units for %d columns" % (len(units), len(names)))
if set(names) != set(csv): sys.exit("FAIL: log.h5's columns differ from log.csv's")
for c, name in enumerate(names):
    bits = [struct.pack('>d', v).hex() for v in data[:, c]]
    if bits != csv[name]: sys.exit("FAIL: column %s differs between log.h5 and log.csv" % name)
print("h5py: %d columns x %d rows of log.h5 equal log.csv bit for bit" % data.shape[::-1])
PY
fi
