#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Prints config/default.yaml as a Markdown table (key | type | default | unit | meaning), for
the README: the YAML file's comments are the one source of every parameter's documentation.

  params_table.py [config/default.yaml]                      print the table
  params_table.py config/default.yaml --check README.md [--junit FILE]
                                                             fail when README.md lacks it
"""
import argparse
import re
import sys
from xml.sax.saxutils import escape


def table(path):
    rows, comment, section = [], [], ""
    with open(path) as f:
        for raw in f:
            line = raw.rstrip("\n")
            stripped = line.strip()
            if stripped.startswith("#"):
                text = stripped.lstrip("#").strip()
                if text and not text.startswith("==="):
                    comment.append(text)
                continue
            if not stripped or stripped.startswith("%") or stripped == "---":
                comment = []
                continue
            match = re.match(r"^(\s*)([a-z0-9_]+):\s*(.*)$", line)
            if not match:
                continue
            indent, key, value = match.groups()
            if not value:  # a section
                section = key
                comment = []
                continue
            full = f"{section}.{key}" if indent else key
            if not indent:
                section = ""
            doc = " ".join(comment)
            described = re.match(r"^(\w+)\s*(\[[^\]]*\])?\s*-\s*(.*)$", doc)
            kind, unit, meaning = (described.group(1), (described.group(2) or "").strip("[]"),
                                   described.group(3)) if described else ("", "", doc)
            rows.append((full, kind, value, unit, meaning.replace("|", "\\|")))
            comment = []
    lines = ["| key | type | default | unit | meaning |", "|---|---|---|---|---|"]
    lines += ["| `{}` | {} | `{}` | {} | {} |".format(*row) for row in rows]
    return "\n".join(lines) + "\n"


def write_junit(path, failure):
    body = f'<failure message="{escape(failure, {chr(34): "&quot;"})}"/>' if failure else ""
    with open(path, "w") as f:
        f.write('<?xml version="1.0" encoding="UTF-8"?>\n'
                f'<testsuite name="parameter_table" tests="1" failures="{int(bool(failure))}">'
                f'<testcase classname="parameter_table" name="readme_matches_default_yaml">{body}'
                '</testcase></testsuite>\n')


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", default="config/default.yaml")
    parser.add_argument("--check", metavar="README", help="check that this file holds the table")
    parser.add_argument("--junit", metavar="FILE", help="with --check: the result as JUnit XML")
    args = parser.parse_args()
    generated = table(args.config)
    if not args.check:
        sys.stdout.write(generated)
        return 0
    with open(args.check) as f:
        failure = "" if generated in f.read() else (
            f"{args.check} does not hold the parameter table of {args.config}: "
            f"regenerate it with scripts/params_table.py {args.config}")
    if args.junit:
        write_junit(args.junit, failure)
    print(failure or f"{args.check}: parameter table up to date")
    return 1 if failure else 0


if __name__ == "__main__":
    sys.exit(main())
