# SPDX-License-Identifier: GPL-3.0-or-later
"""``check --junit FILE``: the pairs of a layout check as JUnit XML, the test report GitLab,
Jenkins and GitHub Actions show (one test case per pair, one test suite per .blend and spec).

A pair that fails its limits is a ``<failure>`` whose message is the first broken limit and
whose text lists every one, the blocking props and the figures; a .blend or spec that could
not be checked (bad input) is one test case with an ``<error>``."""

import xml.etree.ElementTree as ET
from pathlib import Path

from .output import count


def classname(blend, spec):
    """The test cases' class: the .blend's name without its suffix, then the spec's
    (``office.layout``); dots are how the CI tools group classes into packages."""
    parts = [Path(blend).stem if blend else "scene"]
    if spec:
        parts.append(Path(spec).stem)
    return ".".join(p.replace(" ", "_") for p in parts)


def _figures(r):
    if r["reachable"]:
        return (
            f"reachable: {r['length_m']:.2f} m, {r['seconds']:.2f} s of motion, "
            f"cost {r['cost']:.3f}, {count(r['pieces'], 'piece')}, "
            f"{count(r['traversals'], 'traversal')}"
        )
    text = f"unreachable ({r['blocked_reason'] or 'no path'})"
    if r["error"]:
        text += f": {r['error']}"
    return text


def _case(suite, cls, r):
    case = ET.SubElement(
        suite,
        "testcase",
        classname=cls,
        name=r["name"],
        time=f"{r['plan_seconds'] or 0.0:.6f}",
    )
    if r["passed"]:
        return 0
    kind = "unreachable" if not r["reachable"] else "limit"
    fail = ET.SubElement(case, "failure", message=r["failures"][0], type=kind)
    lines = list(r["failures"])
    if r["blocked_by"]:
        lines.append(f"blocking props ({r['blocked_reason']}): {', '.join(r['blocked_by'])}")
    lines.append(_figures(r))
    limits = {k: v for k, v in r["limits"].items() if v is not None}
    lines.append("limits: " + ", ".join(f"{k}={v}" for k, v in sorted(limits.items())))
    fail.text = "\n".join(lines)
    return 1


def write(path, jobs):
    """Write the JUnit XML of ``jobs``: dicts with "blend", "spec" and either "pairs" (the
    results of ``api.check_layout``) or "error" (why that job could not be checked)."""
    root = ET.Element("testsuites", name="motion_patches check")
    total = {"tests": 0, "failures": 0, "errors": 0, "time": 0.0}
    for job in jobs:
        cls = classname(job["blend"], job["spec"])
        suite = ET.SubElement(root, "testsuite", name=cls)
        named = [k for k in ("blend", "spec") if job[k]]
        if named:  # before the cases, as the schema has it
            props = ET.SubElement(suite, "properties")
            for key in named:
                ET.SubElement(props, "property", name=key, value=str(job[key]))
        if job.get("error") is not None:
            case = ET.SubElement(suite, "testcase", classname=cls, name="layout spec", time="0")
            ET.SubElement(case, "error", message=job["error"], type="bad input").text = job["error"]
            counts = {"tests": 1, "failures": 0, "errors": 1, "time": 0.0}
        else:
            failures = sum(_case(suite, cls, r) for r in job["pairs"])
            seconds = sum(r["plan_seconds"] or 0.0 for r in job["pairs"])
            counts = {
                "tests": len(job["pairs"]),
                "failures": failures,
                "errors": 0,
                "time": seconds,
            }
        for k, v in counts.items():
            suite.set(k, f"{v:.6f}" if k == "time" else str(v))
            total[k] += v
    for k, v in total.items():
        root.set(k, f"{v:.6f}" if k == "time" else str(v))
    ET.indent(root)
    Path(path).write_bytes(ET.tostring(root, encoding="utf-8", xml_declaration=True) + b"\n")
