#!/usr/bin/env python3
"""A client of host-sim's live view (the Foxglove WebSocket protocol: subprotocol foxglove.sdk.v1,
the SDK's name for foxglove.websocket.v1), written from the protocol's specification with PyPI's websockets and
jsonschema: it reads the server's advertisement, subscribes to every channel, decodes the
messages of each for a while and validates them against their advertised JSON Schemas.

    python3 client.py ws://127.0.0.1:8765 SECONDS TOPIC[,TOPIC...]

Prints one JSON line: the advertised channels (topic, schema name, encoding) and, per topic,
the messages received and validated; exits 1 when a required topic got none or a message does
not match its schema.
"""

import asyncio
import json
import struct
import sys

import jsonschema
import websockets

# Messages validated per channel (every message is decoded and counted).
VALIDATE = 25


async def main(url, seconds, required):
    async with websockets.connect(url, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"], max_size=None) as ws:
        channels = {}
        counts = {}
        first = {}
        invalid = []
        subscribed = False
        sub_of = {}
        loop = asyncio.get_running_loop()
        end = loop.time() + seconds
        info = None
        while loop.time() < end:
            try:
                msg = await asyncio.wait_for(ws.recv(), timeout=max(0.01, end - loop.time()))
            except asyncio.TimeoutError:
                break
            if isinstance(msg, str):
                m = json.loads(msg)
                if m["op"] == "serverInfo":
                    info = m
                elif m["op"] == "advertise":
                    for c in m["channels"]:
                        channels[c["id"]] = c
                    subs = []
                    for cid in channels:
                        if cid not in sub_of.values():
                            sid = len(sub_of) + 1
                            sub_of[sid] = cid
                            subs.append({"id": sid, "channelId": cid})
                    if subs:
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                        subscribed = True
                continue
            op = msg[0]
            if op == 1:  # message data: subscription id u32, log time u64, payload
                sid, _t = struct.unpack_from("<IQ", msg, 1)
                c = channels[sub_of[sid]]
                payload = json.loads(msg[13:])
                n = counts.get(c["topic"], 0)
                if n < VALIDATE:
                    try:
                        jsonschema.validate(payload, json.loads(c["schema"]))
                    except jsonschema.ValidationError as e:
                        invalid.append(f"{c['topic']}: {e.message}")
                if n == 0:
                    first[c["topic"]] = payload
                counts[c["topic"]] = n + 1
        out = {
            "server": info["name"] if info else None,
            "subscribed": subscribed,
            "channels": sorted(
                (c["topic"], c["schemaName"], c["encoding"], c.get("schemaEncoding")) for c in channels.values()
            ),
            "messages": counts,
            "invalid": invalid[:5],
            "first": first,
        }
        print(json.dumps(out))
        missing = [t for t in required if not counts.get(t)]
        if missing or invalid or not info:
            sys.exit(1)


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1], float(sys.argv[2]), [t for t in sys.argv[3].split(",") if t]))
