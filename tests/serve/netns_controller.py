"""A minimal lockstep controller written from docs/protocol.md alone (standard
library only): subscribes to the arm (the cookie handshake of protocol 2),
answers every state with a velocity command carrying the state's seq, stops
when the states stop, and unsubscribes."""
import socket
import struct
import sys

MAGIC, VERSION, ARM = 1447838018.0, 2, 1
STATE, COMMAND, SUBSCRIBE, SESSION = 1, 2, 4, 5
CHALLENGE, SUBSCRIBED, FULL = 0, 1, 2
host, port = sys.argv[1], int(sys.argv[2])
device = (host, port)
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)


def subscribe(cookie, action):
    # [magic, version, kind, type, seq, time, length, cookie, action]
    sock.sendto(struct.pack("<9d", MAGIC, VERSION, ARM, SUBSCRIBE, 0, 0, 2, cookie, action), device)


# the handshake: a request without the cookie brings a challenge (the cookie of this
# address and port); the request repeated with it subscribes. Lost requests are resent.
cookie, subscribed, tries = 0, False, 0
sock.settimeout(0.25)
while not subscribed:
    tries += 1
    if tries > 40:
        sys.exit("controller: no subscription within 10 s")
    subscribe(cookie, 1)
    try:
        data, _ = sock.recvfrom(65536)
    except socket.timeout:
        continue
    values = struct.unpack("<%dd" % (len(data) // 8), data) if len(data) % 8 == 0 else ()
    if len(values) == 9 and values[:2] == (MAGIC, VERSION) and values[3] == SESSION:
        if values[8] == FULL:
            sys.exit("controller: the arm refused the subscription (table full)")
        cookie = values[7]
        subscribed = values[8] == SUBSCRIBED

answered = 0
sock.settimeout(5.0)
while True:
    try:
        data, _ = sock.recvfrom(65536)
    except socket.timeout:
        break
    sock.settimeout(1.0)  # once the lab answers, a second of silence means the run ended
    if data[:1] == b"{" or len(data) % 8:
        continue
    values = struct.unpack("<%dd" % (len(data) // 8), data)
    if values[:2] != (MAGIC, VERSION) or values[2] != ARM or values[3] != STATE:
        continue  # session replies and anything else
    seq, time = values[4], values[5]
    command = [2.0, 0.1, 0, 0, 0, 0, 0, 0]  # velocity mode, S1 at 0.1 rad/s
    sock.sendto(struct.pack("<%dd" % (7 + len(command)), MAGIC, VERSION, ARM, COMMAND, seq, time, len(command),
                            *command), device)
    answered += 1
subscribe(cookie, 0)
print("controller answered %d states" % answered)
sys.exit(0 if answered >= 500 else 1)
