"""The accuracy gates (bench.campaign.gates) as a JUnit XML report, the format CI systems
(GitHub Actions test reporters, GitLab, Jenkins) display: one test case per gate and method,
a <failure> with the measured value for each gate that failed. Written atomically."""

from __future__ import annotations

import os
import stat
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

from jointbench.bench.campaign.gates import GateResult
from jointbench.bench.campaign.settings import CampaignError
from jointbench.bench.output_files import file_kind
from jointbench.identification.log import atomic_write_text

SUITES = "jointbench campaign"   # the root's name: how an existing report is recognised


def check_junit_path(path: Path) -> None:
    """Before any run: the folder exists and is writable, and the target is absent or a
    regular, writable file that is an earlier report of ours (never a FIFO, a device such as
    /dev/stdout, a link, a read-only file or another program's file). Raises CampaignError."""
    folder = path.parent if str(path.parent) else Path(".")
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        info = None
    except OSError as err:
        raise CampaignError(f"--junit {path}: cannot inspect it: {err.strerror}") from None
    head = ""
    if info is not None and stat.S_ISREG(info.st_mode) and info.st_size > 0:
        try:
            with open(path, "rb") as handle:
                head = handle.read(4096).decode("utf-8", "replace")
        except OSError as err:
            raise CampaignError(f"--junit {path}: cannot read it: {err.strerror}") from None
    kind = None if info is None else file_kind(info.st_mode)
    problem = (f"folder {folder} does not exist" if not folder.is_dir()
               else f"is {kind}, not a regular file: refusing to replace it" if kind
               else "is read-only" if info is not None and (
                   not info.st_mode & 0o222 or not os.access(path, os.W_OK))
               else "refusing to overwrite a file that is not a jointbench JUnit report; "
                    "remove it or choose another name" if head and f'name="{SUITES}"' not in head
               else _unwritable(folder))
    if problem:
        raise CampaignError(f"--junit {path}: {problem}")


def _unwritable(folder: Path) -> str | None:
    """Why the report cannot be written into `folder` (it is written atomically: a temporary
    file there, renamed), found by creating and removing such a file; None when it can."""
    try:
        fd, probe = tempfile.mkstemp(prefix=".jointbench-junit-", suffix=".tmp", dir=folder)
    except OSError as err:
        return f"folder {folder} is not writable ({err.strerror})"
    os.close(fd)
    os.unlink(probe)
    return None


def junit_xml(results: list[GateResult], properties: dict[str, str], wall_s: float) -> str:
    """The report's text: <testsuites><testsuite> with a <testcase> per result."""
    failures = sum(not r.passed for r in results)
    counts = {"tests": str(len(results)), "failures": str(failures), "errors": "0",
              "skipped": "0", "time": f"{wall_s:.3f}"}
    root = ET.Element("testsuites", {"name": SUITES, **counts})
    suite = ET.SubElement(root, "testsuite", {"name": "accuracy gates", **counts})
    props = ET.SubElement(suite, "properties")
    for key, value in properties.items():
        ET.SubElement(props, "property", {"name": key, "value": value})
    for r in results:
        case = ET.SubElement(suite, "testcase", {"classname": f"jointbench.campaign.{r.method}",
                                                 "name": r.name, "time": "0"})
        if not r.passed:
            failure = ET.SubElement(case, "failure", {"message": r.message,
                                                      "type": "AccuracyGate"})
            failure.text = f"{r.name}: {r.message}"
        else:
            ET.SubElement(case, "system-out").text = r.message
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def write_junit(path: Path, results: list[GateResult], properties: dict[str, str],
                wall_s: float) -> None:
    atomic_write_text(Path(path), junit_xml(results, properties, wall_s))
