#!/usr/bin/env python3
"""Validate every message of an uncoil run.mcap with readers this project did not write.

Reads the file with the `mcap` package (PyPI) and decodes each message with Google's
`protobuf` package:
- a channel whose schema is a Foxglove one (`foxglove.*`) is decoded with the class that
  Foxglove publishes for it (PyPI `foxglove-schemas-protobuf`), not with the schema the file
  carries; that embedded schema must describe the same fields (names, numbers, types,
  labels) as the published one;
- a channel with the project's own schema (`uncoil.*`) is decoded with a class built from the
  descriptor set embedded in the file;
- every message must decode with no field unknown to its schema, at any depth, every
  channel is protobuf-encoded, and its log times never go back;
- every chunk has message indexes (Foxglove Studio reads no chunk without them).

With --self-test it also writes a copy of the file in which one /scene message is broken
(its last byte cut off) and checks that the copy fails validation.

Usage:
  pip install mcap==1.6.0 protobuf==7.36.2 foxglove-schemas-protobuf==0.4.0
  python3 tools/validate_mcap.py RUN.mcap [--self-test]

Exit status: 0 valid (and the broken copy rejected), 1 otherwise.
"""

import argparse
import importlib
import os
import sys
import tempfile

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory, unknown_fields
from mcap.reader import make_reader
from mcap.writer import Writer


def published(name):
    """Foxglove's published class for a schema name such as foxglove.SceneUpdate."""
    short = name.split(".", 1)[1]
    module = importlib.import_module(f"foxglove_schemas_protobuf.{short}_pb2")
    return getattr(module, short)


def embedded(schema):
    """The class of the message a schema names, built from the descriptor set it carries."""
    files = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def shape(desc, seen=None):
    """Fields of a message descriptor and of the messages it nests, as comparable tuples."""
    seen = set() if seen is None else seen
    if desc.full_name in seen:
        return []
    seen.add(desc.full_name)
    out = []
    for f in desc.fields:
        out.append((desc.full_name, f.name, f.number, f.type, f.is_repeated))
        if f.message_type is not None:
            out.extend(shape(f.message_type, seen))
    return sorted(out)


def unknown(message):
    """Counts the fields of `message` and of the messages in it unknown to their schemas."""
    n = len(unknown_fields.UnknownFieldSet(message))
    for field, value in message.ListFields():
        if field.message_type is None:
            continue
        for m in value if field.is_repeated else [value]:
            n += unknown(m)
    return n


def validate(path):
    """Returns (messages checked per topic, list of problems)."""
    problems = []
    counts = {}
    classes = {}
    last_time = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is None:
            return counts, ["no summary section: the file is not finished"]
        for chunk in summary.chunk_indexes:
            if chunk.message_index_length == 0:
                problems.append(f"chunk at {chunk.chunk_start_offset} has no message index")
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            topic = channel.topic
            if schema is None or schema.encoding != "protobuf":
                problems.append(f"{topic}: schema encoding is not protobuf")
                continue
            if channel.message_encoding != "protobuf":
                problems.append(f"{topic}: message encoding {channel.message_encoding}")
                continue
            if topic not in classes:
                try:
                    own = embedded(schema)
                    if schema.name.startswith("foxglove."):
                        cls = published(schema.name)
                        if shape(cls.DESCRIPTOR) != shape(own.DESCRIPTOR):
                            problems.append(
                                f"{topic}: the embedded {schema.name} differs from the "
                                "published one"
                            )
                    else:
                        cls = own
                except Exception as e:  # noqa: BLE001 - any failure is a finding
                    problems.append(f"{topic}: schema {schema.name}: {e}")
                    cls = None
                classes[topic] = cls
            cls = classes[topic]
            if cls is None:
                continue
            if message.log_time < last_time.get(topic, 0):
                problems.append(f"{topic}: log time goes back at {message.log_time}")
            last_time[topic] = message.log_time
            try:
                decoded = cls.FromString(message.data)
                if unknown(decoded):
                    raise ValueError(f"{unknown(decoded)} fields unknown to {schema.name}")
            except Exception as e:  # noqa: BLE001 - any failure is a finding
                if len(problems) < 20:
                    problems.append(f"{topic} at {message.log_time} ns: {e}")
                continue
            counts[topic] = counts.get(topic, 0) + 1
    return counts, problems


def broken_copy(path, out):
    """Writes a copy of `path` with the first /scene message's last byte cut off."""
    with open(path, "rb") as f, open(out, "wb") as g:
        reader = make_reader(f)
        writer = Writer(g)
        writer.start()
        schemas = {}
        channels = {}
        broke = False
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(
                    schema.name, schema.encoding, schema.data
                )
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(
                    channel.topic,
                    channel.message_encoding,
                    schemas[schema.id],
                    channel.metadata,
                )
            data = message.data
            if channel.topic == "/scene" and not broke:
                data = data[:-1]
                broke = True
            writer.add_message(
                channels[channel.id], message.log_time, data, message.publish_time,
                message.sequence,
            )
        writer.finish()
    return broke


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mcap")
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()

    counts, problems = validate(args.mcap)
    for p in problems:
        print(f"invalid: {p}")
    for topic, n in sorted(counts.items()):
        print(f"{topic}: {n} messages decoded")
    ok = not problems and {"/scene", "/state", "/events", "/tf"} <= counts.keys()
    if not ok and not problems:
        print("invalid: a channel is missing")
    if args.self_test:
        with tempfile.TemporaryDirectory() as tmp:
            copy = os.path.join(tmp, "broken.mcap")
            if not broken_copy(args.mcap, copy):
                print("self-test: no /scene message to break")
                ok = False
            else:
                _, broken = validate(copy)
                if broken:
                    print(f"self-test: the broken copy is rejected ({broken[0]})")
                else:
                    print("self-test FAILED: the broken copy passed")
                    ok = False
    print("valid" if ok else "INVALID")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
