#!/usr/bin/env python3
"""Validate every message of an uncoil run.mcap with readers this project did not write.

Reads the file with the `mcap` package (PyPI) and checks each message with `jsonschema`:
- a channel whose schema is a Foxglove one (`foxglove.*`) must carry the official schema
  text (equal, as JSON, to the schema that the npm package @foxglove/schemas publishes in
  dist/jsonschema), and its messages are validated against that official schema;
- a channel with the project's own schema (`uncoil.*`) is validated against the schema
  embedded in the file, which must itself be a valid JSON schema;
- every channel is JSON-encoded with a `jsonschema` schema, and its log times never go back;
- every chunk has message indexes (Foxglove Studio reads no chunk without them).

With --self-test it also writes a copy of the file in which one /scene message is broken
(an entity's frame_id becomes a number) and checks that the copy fails validation.

Usage:
  npm pack @foxglove/schemas@2.1.0 && tar xzf foxglove-schemas-2.1.0.tgz
  python3 tools/validate_mcap.py RUN.mcap --foxglove-package package [--self-test]

Exit status: 0 valid (and the broken copy rejected), 1 otherwise.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

import jsonschema
from mcap.reader import make_reader
from mcap.writer import Writer


def official_schemas(package_dir):
    """The JSON schemas of @foxglove/schemas, by title (e.g. foxglove.SceneUpdate).

    The package ships them as the exports of dist/jsonschema/index.js; node prints them.
    """
    index = os.path.abspath(os.path.join(package_dir, "dist", "jsonschema", "index.js"))
    script = "process.stdout.write(JSON.stringify(require(process.argv[1])))"
    out = subprocess.run(
        ["node", "-e", script, index], check=True, capture_output=True, text=True
    ).stdout
    schemas = {}
    for value in json.loads(out).values():
        if isinstance(value, dict) and "title" in value:
            schemas[value["title"]] = value
    if "foxglove.SceneUpdate" not in schemas:
        sys.exit(f"error: no foxglove.SceneUpdate schema in {index}")
    return schemas


def validate(path, official):
    """Returns (messages checked per topic, list of problems)."""
    problems = []
    counts = {}
    validators = {}
    last_time = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is None:
            problems.append("no summary section: the file is not finished")
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            topic = channel.topic
            if topic not in validators:
                validators[topic] = None
                if schema is None or schema.encoding != "jsonschema":
                    problems.append(f"{topic}: schema encoding is not jsonschema")
                elif channel.message_encoding != "json":
                    problems.append(f"{topic}: message encoding is not json")
                else:
                    embedded = json.loads(schema.data)
                    if schema.name.startswith("foxglove."):
                        ref = official.get(schema.name)
                        if ref is None:
                            problems.append(f"{topic}: {schema.name} is no official schema")
                            continue
                        if embedded != ref:
                            problems.append(
                                f"{topic}: the {schema.name} schema in the file differs "
                                "from the official one"
                            )
                        use = ref
                    else:
                        use = embedded
                    cls = jsonschema.validators.validator_for(use)
                    cls.check_schema(use)
                    validators[topic] = cls(use)
            validator = validators[topic]
            counts[topic] = counts.get(topic, 0) + 1
            if message.log_time < last_time.get(topic, 0):
                problems.append(f"{topic}: message {message.sequence} goes back in time")
            last_time[topic] = message.log_time
            if validator is None:
                continue
            try:
                data = json.loads(message.data)
            except ValueError as e:
                problems.append(f"{topic} #{message.sequence}: not JSON: {e}")
                continue
            for error in validator.iter_errors(data):
                path_text = "/".join(str(p) for p in error.absolute_path)
                problems.append(
                    f"{topic} #{message.sequence} at /{path_text}: {error.message[:200]}"
                )
    if summary is not None:
        # Foxglove Studio refuses a chunk without message indexes.
        for c in summary.chunk_indexes:
            if c.message_index_length == 0:
                problems.append(f"chunk at {c.chunk_start_offset} has no message index")
    if summary is not None and summary.statistics is not None:
        total = sum(counts.values())
        if summary.statistics.message_count != total:
            problems.append(
                f"summary counts {summary.statistics.message_count} messages, read {total}"
            )
    return counts, problems


def write_broken_copy(src, dst):
    """Copies src to dst, breaking the first /scene message's first entity."""
    broken = False
    with open(src, "rb") as f, open(dst, "wb") as out:
        reader = make_reader(f)
        writer = Writer(out)
        writer.start(profile="", library="validate_mcap.py")
        schema_ids, channel_ids = {}, {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema.id not in schema_ids:
                schema_ids[schema.id] = writer.register_schema(
                    schema.name, schema.encoding, schema.data
                )
            if channel.id not in channel_ids:
                channel_ids[channel.id] = writer.register_channel(
                    channel.topic, channel.message_encoding, schema_ids[schema.id]
                )
            data = message.data
            if channel.topic == "/scene" and not broken:
                msg = json.loads(data)
                msg["entities"][0]["frame_id"] = 5
                data = json.dumps(msg).encode()
                broken = True
            writer.add_message(
                channel_ids[channel.id],
                message.log_time,
                data,
                message.publish_time,
                message.sequence,
            )
        writer.finish()
    return broken


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("mcap", help="the run.mcap to check")
    parser.add_argument(
        "--foxglove-package",
        required=True,
        help="the unpacked npm package @foxglove/schemas (holding dist/jsonschema)",
    )
    parser.add_argument(
        "--self-test",
        action="store_true",
        help="also check that a copy with one broken message fails",
    )
    args = parser.parse_args()
    official = official_schemas(args.foxglove_package)

    passed, failed = 0, 0
    counts, problems = validate(args.mcap, official)
    for p in problems[:20]:
        print(f"  {p}")
    summary = ", ".join(f"{t} {n}" for t, n in sorted(counts.items()))
    if problems:
        print(f"{args.mcap}: INVALID, {len(problems)} problems ({summary})")
        failed += 1
    else:
        print(f"{args.mcap}: every message valid ({summary})")
        passed += 1

    if args.self_test:
        with tempfile.TemporaryDirectory() as tmp:
            copy = os.path.join(tmp, "broken.mcap")
            broken = []
            if write_broken_copy(args.mcap, copy):
                _, broken = validate(copy, official)
            if broken:
                print(f"self-test: the broken copy is rejected ({broken[0]})")
                passed += 1
            else:
                print("self-test: FAILED, a broken /scene message was accepted")
                failed += 1
    print(f"validate_mcap: {passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
