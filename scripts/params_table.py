#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Prints config/default.yaml as a Markdown table (key | type | default | unit | meaning), for
the README: the YAML file's comments are the one source of every parameter's documentation."""
import re
import sys


def main(path):
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
    print("| key | type | default | unit | meaning |")
    print("|---|---|---|---|---|")
    for row in rows:
        print("| `{}` | {} | `{}` | {} | {} |".format(*row))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "config/default.yaml")
