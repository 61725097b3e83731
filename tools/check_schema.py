#!/usr/bin/env python3
"""Validates a JSON file against a JSON Schema, the subset docs/bench.schema.json uses (type,
enum, required, properties, additionalProperties, items, minItems, maxItems, minimum, oneOf,
$ref to #/$defs/...). No third-party module needed.

usage: check_schema.py SCHEMA.json FILE.json    (exit 0: valid; 1: one line naming the problem)
"""
import json
import sys

TYPES = {"object": dict, "array": list, "string": str, "boolean": bool, "null": type(None)}


def is_type(v, t):
    if t == "integer":
        return isinstance(v, int) and not isinstance(v, bool)
    if t == "number":
        return isinstance(v, (int, float)) and not isinstance(v, bool)
    return isinstance(v, TYPES[t])


def check(v, s, root, path):
    """Returns None if v is valid, else a message."""
    if "$ref" in s:
        ref = s["$ref"]
        node = root
        for part in ref.lstrip("#/").split("/"):
            node = node[part]
        return check(v, node, root, path)
    if "oneOf" in s:
        errs = [check(v, sub, root, path) for sub in s["oneOf"]]
        if sum(e is None for e in errs) != 1:
            return "%s: matches %d of oneOf (%s)" % (path, sum(e is None for e in errs), "; ".join(e for e in errs if e))
        return None
    if "type" in s:
        ts = s["type"] if isinstance(s["type"], list) else [s["type"]]
        if not any(is_type(v, t) for t in ts):
            return "%s: %r is not %s" % (path, v, "/".join(ts))
    if "enum" in s and v not in s["enum"]:
        return "%s: %r not one of %s" % (path, v, s["enum"])
    if "minimum" in s and is_type(v, "number") and v < s["minimum"]:
        return "%s: %r below %r" % (path, v, s["minimum"])
    if isinstance(v, dict):
        for k in s.get("required", []):
            if k not in v:
                return "%s: missing %r" % (path, k)
        props = s.get("properties", {})
        for k, x in v.items():
            sub = props.get(k, s.get("additionalProperties"))
            if isinstance(sub, dict):
                e = check(x, sub, root, path + "." + k)
                if e:
                    return e
    if isinstance(v, list):
        if len(v) < s.get("minItems", 0) or len(v) > s.get("maxItems", len(v)):
            return "%s: %d items" % (path, len(v))
        if "items" in s:
            for i, x in enumerate(v):
                e = check(x, s["items"], root, "%s[%d]" % (path, i))
                if e:
                    return e
    return None


def main():
    if len(sys.argv) != 3:
        print("usage: check_schema.py SCHEMA.json FILE.json")
        sys.exit(2)
    try:
        schema = json.load(open(sys.argv[1]))
        doc = json.load(open(sys.argv[2]))
    except (OSError, ValueError) as e:
        print("check_schema: %s" % e)
        sys.exit(1)
    e = check(doc, schema, schema, "$")
    if e:
        print("check_schema: %s: %s" % (sys.argv[2], e))
        sys.exit(1)
    print("check_schema: %s: valid" % sys.argv[2])


main()
