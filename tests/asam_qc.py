#!/usr/bin/env python3
"""Runs ASAM's own quality checkers on pedsynth's exports and fails on any issue.

    python3 tests/asam_qc.py xodr FILE.xodr [...]     # asam-qc-opendrive (qc_opendrive)
    python3 tests/asam_qc.py xosc FILE.xosc [...]     # asam-qc-openscenarioxml (qc_openscenario)
    (--quiet: print only problems and the summary line)

Each file gets its own checker configuration (every checker of the bundle runs: the bundles run all their
checks whatever the configuration lists), then the result file (.xqar) is read back with the checkers' own
qc_baselib. A file passes when the bundle reports zero issues and every checker completed; a checker may be
skipped only because the rule does not apply to the file's declared standard version (that is how the bundles
scope rules), and those are listed; for OpenDRIVE a copy declared 1.8 runs the 1.8-only rule, and every
checker of the bundle must have completed on the file or its copy. Exits 1 on the first failing file (in the order
given), printing its issues. Files are checked in parallel, one checker process per CPU.
"""

import concurrent.futures
import os
import subprocess
import sys
import tempfile

from qc_baselib import Result, StatusType

VERBOSE = True
BUNDLES = {"xodr": ("qc_opendrive", "xodrBundle"), "xosc": ("qc_openscenario", "xoscBundle")}


def check(kind: str, path: str, work: str) -> tuple[list[str], set[str], set[str]]:
    command, bundle = BUNDLES[kind]
    result_file = os.path.join(work, os.path.basename(path) + ".xqar")
    config = os.path.join(work, os.path.basename(path) + ".config.xml")
    with open(config, "w") as f:
        f.write(
            '<?xml version="1.0" encoding="UTF-8"?>\n<Config>\n'
            f'<Param name="InputFile" value="{os.path.abspath(path)}"/>\n'
            f'<CheckerBundle application="{bundle}">\n'
            f'<Param name="resultFile" value="{result_file}"/>\n'
            "</CheckerBundle>\n</Config>\n"
        )
    run = subprocess.run([command, "-c", config], capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"{path}: {command} exited {run.returncode}\n{run.stdout}\n{run.stderr}")
    result = Result()
    result.load_from_file(result_file)
    problems, skipped, completed, all_ids = [], [], set(), set()
    for checker in result.get_checker_results(bundle):
        all_ids.add(checker.checker_id)
        issues = result.get_issues(bundle, checker.checker_id)
        for issue in issues:
            where = []
            for loc in issue.locations:
                where += [f"line {f.row}" for f in loc.file_location] + [x.xpath for x in loc.xml_location]
                where.append(loc.description)
            problems.append(f"{checker.checker_id}: {issue.level.name} {issue.description}: {'; '.join(where[:4])}")
        if checker.status == StatusType.COMPLETED:
            completed.add(checker.checker_id)
        elif checker.status == StatusType.SKIPPED and "Version" in (checker.summary or ""):
            skipped.append(f"{checker.checker_id} ({checker.summary})")
        else:
            problems.append(f"{checker.checker_id}: status {checker.status} ({checker.summary})")
    if VERBOSE:
        print(f"{path}: {len(completed)} checks completed, {len(problems)} problems, {len(skipped)} not applicable to its version")
        for s in skipped:
            print(f"  not applicable: {s}")
    return problems, completed, all_ids


def main() -> None:
    if len(sys.argv) < 3 or sys.argv[1] not in BUNDLES:
        sys.exit(__doc__)
    global VERBOSE
    VERBOSE = "--quiet" not in sys.argv
    kind, files = sys.argv[1], [a for a in sys.argv[2:] if a != "--quiet"]
    checks = 0
    with tempfile.TemporaryDirectory() as work:
        jobs = []
        for path in files:
            copies = [path]
            if kind == "xodr":
                # The OpenDRIVE bundle scopes one rule to 1.8 (junctions.connection.one_link_to_incoming) and
                # another to <= 1.7; our 1.7 files are valid 1.8 too, so a copy declared 1.8 runs the former.
                with open(path) as f:
                    text = f.read()
                copy = os.path.join(work, os.path.basename(path) + ".as-1.8.xodr")
                with open(copy, "w") as f:
                    f.write(text.replace('revMinor="7"', 'revMinor="8"', 1))
                copies.append(copy)
            jobs.append((path, copies))
        with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
            results = {p: pool.submit(check, kind, p, work) for _, copies in jobs for p in copies}
            for path, copies in jobs:
                completed, all_ids = set(), set()
                for p in copies:
                    problems, done, ids = results[p].result()
                    if problems:
                        print("\n".join(problems[:40]))
                        sys.exit(f"{p}: {len(problems)} problems reported by ASAM's checker")
                    completed |= done
                    all_ids |= ids
                if completed != all_ids:
                    sys.exit(f"{path}: checks that never ran: {sorted(all_ids - completed)}")
                if VERBOSE:
                    print(f"{path}: all {len(all_ids)} checks of the bundle ran, zero issues")
                checks = len(all_ids)
    print(f"asam_qc: {len(files)} {kind} files, all {checks} checks of {BUNDLES[kind][0]} ran on each, zero issues")


if __name__ == "__main__":
    main()
