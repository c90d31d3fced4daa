"""A minimal lockstep controller written from docs/protocol.md alone (standard
library only): subscribes to the arm, answers every state with a velocity
command carrying the state's seq, stops when the states stop."""
import socket
import struct
import sys

MAGIC = 1447838018.0
host, port = sys.argv[1], int(sys.argv[2])
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.settimeout(5.0)
sock.sendto(struct.pack("<7d", MAGIC, 1, 1, 3, 0, 0, 0), (host, port))  # describe: subscribes
answered = 0
while True:
    try:
        data, _ = sock.recvfrom(65536)
    except socket.timeout:
        break
    sock.settimeout(1.0)  # once the lab answers, a second of silence means the run ended
    if data[:1] == b"{":
        continue
    values = struct.unpack("<%dd" % (len(data) // 8), data)
    if values[0] != MAGIC or values[2] != 1 or values[3] != 1:
        continue
    seq, time = values[4], values[5]
    command = [2.0, 0.1, 0, 0, 0, 0, 0, 0]  # velocity mode, S1 at 0.1 rad/s
    sock.sendto(struct.pack("<%dd" % (7 + len(command)), MAGIC, 1, 1, 2, seq, time, len(command), *command),
                (host, port))
    answered += 1
print("controller answered %d states" % answered)
sys.exit(0 if answered >= 500 else 1)
