#!/usr/bin/env python3
"""Watch `uncoil run --live` with a client written against the Foxglove WebSocket protocol's
published specification (github.com/foxglove/ws-protocol, docs/spec.md), not with the SDK.

It starts the run itself (a bounded scene), connects while the run goes, offering the
subprotocol the Foxglove SDK's server negotiates (`foxglove.sdk.v1`), subscribes to every
advertised channel, and decodes each message it receives with Google's `protobuf` package:
the Foxglove channels with the classes Foxglove publishes on PyPI
(`foxglove-schemas-protobuf`), the project's own with the schema the server advertises.

It checks that the four channels are advertised with their schemas, that messages of each
arrive while the run goes, that `/state`'s times go forward, that simulated time advances at
the pace asked for, and that the run then ends with exit code 0.

Usage:
  pip install websockets==15.0.1 protobuf==7.36.2 foxglove-schemas-protobuf==0.4.0
  python3 tools/live_client.py [--pace 0.5] [--port 18765] [UNCOIL_BINARY] -- SCENE [ARGS...]

`--pace 0` runs unpaced, as fast as the run goes, and skips the pace check: with it, the
run's wall and CPU time it prints are the cost of serving one viewer (compare with the same
run without `--live`).

Exit status: 0 if every check passed, 1 otherwise.
"""

import argparse
import asyncio
import base64
import json
import os
import struct
import subprocess
import sys
import time

import websockets
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from validate_mcap import published, unknown  # noqa: E402

SUBPROTOCOL = "foxglove.sdk.v1"
TOPICS = {
    "/scene": "foxglove.SceneUpdate",
    "/state": "uncoil.State",
    "/events": "uncoil.Event",
    "/tf": "foxglove.FrameTransforms",
}


def advertised_class(channel):
    """The class to decode a channel's messages with."""
    if channel["schemaName"].startswith("foxglove."):
        return published(channel["schemaName"])
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))


async def connect(url, deadline):
    """Connects as soon as the server listens."""
    while True:
        try:
            return await websockets.connect(
                url, subprotocols=[SUBPROTOCOL], max_size=None, open_timeout=5
            )
        except OSError:
            if time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.05)


async def watch(url, problems):
    """Receives until the server closes; returns per-topic (count, first and last receipt
    wall time, first and last /state t_s)."""
    ws = await connect(url, time.monotonic() + 60)
    if ws.subprotocol != SUBPROTOCOL:
        problems.append(f"negotiated {ws.subprotocol!r}, not {SUBPROTOCOL}")
    channels = {}
    subs = {}
    seen = {}
    states = []
    try:
        async for frame in ws:
            now = time.monotonic()
            if isinstance(frame, str):
                msg = json.loads(frame)
                if msg["op"] == "advertise":
                    new = []
                    for ch in msg["channels"]:
                        channels[ch["id"]] = ch
                        if ch["encoding"] != "protobuf":
                            problems.append(f"{ch['topic']}: encoding {ch['encoding']}")
                        if TOPICS.get(ch["topic"]) != ch["schemaName"]:
                            problems.append(f"{ch['topic']}: schema {ch['schemaName']}")
                        sub = len(subs) + 1
                        subs[sub] = (ch["topic"], advertised_class(ch))
                        new.append({"id": sub, "channelId": ch["id"]})
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))
                continue
            if frame[0] != 1:
                continue
            sub, stamp = struct.unpack_from("<IQ", frame, 1)
            topic, cls = subs[sub]
            decoded = cls.FromString(frame[13:])
            if unknown(decoded):
                problems.append(f"{topic}: fields unknown to its schema")
            count, first, _ = seen.get(topic, (0, now, now))
            seen[topic] = (count + 1, first, now)
            if topic == "/state":
                states.append((now, decoded.t_s, stamp))
    except websockets.ConnectionClosed:
        pass
    return seen, states


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pace", type=float, default=0.5)
    parser.add_argument("--port", type=int, default=18765)
    parser.add_argument("binary", nargs="?", default="target/release/uncoil")
    parser.add_argument("run_args", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    run_args = [a for a in args.run_args if a != "--"]
    addr = f"127.0.0.1:{args.port}"
    cmd = [args.binary, "run", *run_args, "--live", addr]
    if args.pace > 0:
        cmd += ["--pace", str(args.pace)]
    print("running:", " ".join(cmd))
    start = time.perf_counter()
    run = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    problems = []
    seen, states = asyncio.run(watch(f"ws://{addr}", problems))
    err = run.stderr.read()
    _, status, usage = os.wait4(run.pid, 0)
    code = os.waitstatus_to_exitcode(status)
    print(f"the run: wall {time.perf_counter() - start:.2f} s, "
          f"cpu {usage.ru_utime + usage.ru_stime:.2f} s")
    if code != 0:
        problems.append(f"the run exited with {code}: {err.strip()[-500:]}")
    for topic in TOPICS:
        n, first, last = seen.get(topic, (0, 0, 0))
        print(f"{topic}: {n} messages over {last - first:.2f} s of wall time")
        if n < 2:
            problems.append(f"{topic}: {n} messages received")
    if len(states) >= 2:
        if any(b[1] < a[1] for a, b in zip(states, states[1:])):
            problems.append("/state: t_s goes back")
        wall = states[-1][0] - states[0][0]
        sim = states[-1][1] - states[0][1]
        rate = sim / wall if wall > 0 else float("inf")
        print(f"/state: {sim:.3f} s simulated in {wall:.3f} s: {rate:.3f} x real time "
              f"(asked {args.pace or 'unpaced'})")
        # The run may fall behind its pace (a slow step), never run ahead of it.
        if args.pace > 0 and not 0.5 * args.pace <= rate <= 1.1 * args.pace:
            problems.append(f"paced at {rate:.3f} x real time, asked {args.pace}")
    for p in problems:
        print(f"problem: {p}")
    print("live view ok" if not problems else "LIVE VIEW FAILED")
    return 0 if not problems else 1


if __name__ == "__main__":
    sys.exit(main())
