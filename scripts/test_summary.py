#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Counts the test cases in a catkin test_results folder (gtest and rostest JUnit XML).

catkin_test_results adds a gtest file's <testsuites> total to its <testsuite> totals and so
counts every gtest case twice; this counts <testcase> elements instead. Prints the failing
cases and a closing 'N passed, N failed' line; exits 1 when anything failed or nothing ran.
"""
import pathlib
import sys
import xml.etree.ElementTree as ElementTree


def main(folder):
    passed, failed, skipped, broken_files = 0, [], 0, []
    for path in sorted(pathlib.Path(folder).rglob("*.xml")):
        try:
            root = ElementTree.parse(path).getroot()
        except ElementTree.ParseError as error:
            broken_files.append(f"{path}: {error}")
            continue
        cases = list(root.iter("testcase"))
        if not cases and root.get("errors", "0") != "0":
            broken_files.append(f"{path}: test did not run (errors={root.get('errors')})")
        for case in cases:
            name = f"{path.name}: {case.get('classname', '')}.{case.get('name', '')}"
            if case.find("failure") is not None or case.find("error") is not None:
                failed.append(name)
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
            else:
                passed += 1
    for name in failed:
        print(f"FAILED: {name}")
    for entry in broken_files:
        print(f"BROKEN: {entry}")
    total_failed = len(failed) + len(broken_files)
    print(f"{passed} passed, {total_failed} failed, {skipped} skipped")
    if passed + total_failed == 0:
        print("no test ran", file=sys.stderr)
        return 1
    return 1 if total_failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/test_results"))
