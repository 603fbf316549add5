"""The UDP end a pymavlink test script listens on for the companion's `udpout:` stream."""
import socket


def loopback_socket(timeout_s):
    """A socket bound to a free loopback port, with a receive buffer large enough that a replay
    running faster than real time does not overflow it; returns the socket and its port."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(timeout_s)
    return sock, sock.getsockname()[1]
