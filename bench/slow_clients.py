#!/usr/bin/env python3
"""Latency of /healthz and a point query while slow clients hold connections (issue 18).

Opens SLOW connections to the server (half send a request line and trickle header bytes, half
declare a body and never send it), then times REQUESTS requests of each kind, each on a new
connection, and prints p50 / p99 / max. Exit 1 if any timed request fails. Slow clients are closed
at the end (the server cuts them off itself at read_timeout_s / body_timeout_s).

Usage: slow_clients.py HOST PORT SLOW [REQUESTS] [POINT_QUERY]
"""
import http.client
import socket
import statistics
import sys
import threading
import time

host, port, slow = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
requests = int(sys.argv[4]) if len(sys.argv) > 4 else 50
point_query = sys.argv[5] if len(sys.argv) > 5 else "/v1/shadow?x=0&y=0&z=0"

clients = []
for i in range(slow):
    s = socket.create_connection((host, port))
    if i % 2 == 0:
        s.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n")
    else:
        s.sendall(b"POST /v1/shadow HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Content-Length: 100000\r\n\r\n{\"points\"")
    clients.append(s)

stop = threading.Event()
def trickle():
    while not stop.is_set():
        for s in clients[::2]:
            try:
                s.sendall(b"X")
            except OSError:
                pass
        time.sleep(0.2)
trickler = threading.Thread(target=trickle)
trickler.start()
time.sleep(0.3)

def timed(path):
    start = time.perf_counter()
    c = http.client.HTTPConnection(host, port, timeout=30)
    c.request("GET", path)
    r = c.getresponse()
    r.read()
    c.close()
    return r.status, time.perf_counter() - start

failures = 0
results = {}
for name, path in (("/healthz", "/healthz"), ("point query", point_query)):
    times = []
    for _ in range(requests):
        status, seconds = timed(path)
        failures += status != 200
        times.append(seconds)
    times.sort()
    results[name] = times
stop.set()
trickler.join()
for s in clients:
    s.close()
for name, times in results.items():
    p99 = times[min(len(times) - 1, int(round(0.99 * (len(times) - 1))))]
    print(f"{name + ' with ' + str(slow) + ' slow clients':<36} p50 {statistics.median(times) * 1e3:7.2f} ms"
          f"   p99 {p99 * 1e3:7.2f} ms   max {times[-1] * 1e3:7.2f} ms   ({len(times)} requests)")
if failures:
    print(f"{failures} requests failed", file=sys.stderr)
    sys.exit(1)
