#!/usr/bin/env python3
"""Mutation testing for mjtether: plant one bug at a time and check that the suite catches it.

Each entry of the catalogue (tools/mutations.cfg) names a source file, a text that must occur
exactly once in it, its replacement, and the physics or behaviour the change breaks. For each
entry this script
  1. copies the repository (its tracked and unignored files, as they are in the working tree)
     into a scratch tree outside it, and keeps a build directory there (the second run only
     recompiles what changed; ccache serves the restored files);
  2. applies the one replacement to the scratch copy, rebuilds, runs the fast suite (every
     CTest test but the labels in FAST_EXCLUDE), and records the tests that failed;
  3. restores the file.
A mutant is "caught" when a test fails (or times out), "survived" when all pass. A pattern that
does not occur exactly once, or a mutant that does not compile, is an "error" of the catalogue,
never counted as caught. Entries marked `equivalent` (a change that cannot alter behaviour,
with the reason) are run too; they are expected to survive and are left out of the score:
    score = caught / (caught + survived), over the non-equivalent entries.

The working tree is never written to: only the scratch directory (default
$TMPDIR/mjtether-mutation) is. The exception is --in-place, for a disposable clone whose build
directory is already built (.ci/run): each mutant is planted in the repository's own file and
built in that build directory (no second full build), and the file is restored afterwards,
whatever happens; files with uncommitted changes are refused.

An entry may name `first`, a ctest regex of the tests known to catch it: they run first, and
the whole fast suite runs only if they all pass (a mutant is still "caught" only by a failing
test). This keeps a sample run to a rebuild and a test or two per entry.

Usage:
  tools/mutate.py                 # the whole catalogue (about 1-2 min per entry on 2 cores)
  tools/mutate.py --sample        # the entries marked `sample = yes`
  tools/mutate.py --sample --in-place --no-baseline   # what .ci/run does, in its clone's build/
  tools/mutate.py --only ID,ID    # some entries
  tools/mutate.py --list          # list the entries and check their patterns, build nothing
  tools/mutate.py --report docs/mutation_results.md   # also write the table as Markdown
Exit status: 0 when no non-equivalent mutant survived and no entry is an error, 1 otherwise,
2 on a usage error or when the unmutated suite fails.
"""

import argparse
import configparser
import os
import pathlib
import shutil
import re
import signal
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parent.parent
# The fast suite: every CTest test but the labels valgrind (minutes per test) and long (the
# hour-long runs), and but the renderer's tests (pixels and videos; no catalogue entry touches
# the renderer, and they take a third of the suite's time).
FAST_EXCLUDE_LABELS = "valgrind|long|scene_fuzz"  # scene_fuzz: 80+ s, physics covered elsewhere
FAST_EXCLUDE_NAMES = "^Render"
TEST_TIMEOUT = 300  # [s] per test; a mutant that makes a test hang is caught by the timeout


def unfold(value):
  """A value's continuation lines start with '|' (configparser strips their indentation, the
  '|' keeps it): 'a\n|    b' is 'a\n    b'."""
  lines = value.split("\n")
  for k in range(1, len(lines)):
    if not lines[k].startswith("|"):
      sys.exit(f"continuation line without '|': {lines[k]!r}")
    lines[k] = lines[k][1:]
  return "\n".join(lines)


def load_catalogue(path):
  cfg = configparser.ConfigParser(interpolation=None, comment_prefixes=("#",),
                                  empty_lines_in_values=False)
  cfg.optionxform = str
  with open(path) as f:
    cfg.read_file(f)
  entries = []
  for name in cfg.sections():
    s = cfg[name]
    missing = [k for k in ("file", "find", "replace", "breaks") if k not in s]
    if missing:
      sys.exit(f"{path}: [{name}]: missing {', '.join(missing)}")
    entries.append({
        "id": name,
        "file": s["file"],
        "find": unfold(s["find"]),
        "replace": unfold(s["replace"]),
        "breaks": " ".join(s["breaks"].split()),
        "sample": s.get("sample", "no").strip() == "yes",
        "equivalent": " ".join(s.get("equivalent", "").split()),
        "first": s.get("first", "").strip(),
    })
  return entries


def run(cmd, cwd=None, log=None, timeout=None):
  """Runs cmd; returns (exit status, output). Output also goes to `log` when given."""
  p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                     timeout=timeout)
  if log:
    log.write(f"$ {' '.join(map(str, cmd))}\n{p.stdout}\n")
    log.flush()
  return p.returncode, p.stdout


def sync_tree(scratch):
  """Copies the repository's tracked and unignored files into scratch/tree. Files whose content
  is unchanged keep their time stamps (no rebuild); changed ones are written anew and get the
  current time, so that ninja rebuilds them even when the repository's copy is older."""
  tree = scratch / "tree"
  tree.mkdir(parents=True, exist_ok=True)
  files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=REPO,
                         check=True, stdout=subprocess.PIPE).stdout
  keep = {f.decode() for f in files.split(b"\0") if f}
  for name in sorted(keep):
    src, dst = REPO / name, tree / name
    if not src.is_file():
      continue  # deleted in the working tree but not yet in the index
    data = src.read_bytes()
    if dst.is_file() and dst.read_bytes() == data:
      continue
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_bytes(data)
    shutil.copymode(src, dst)
  # Remove scratch files the repository no longer has (a renamed source would still be globbed).
  for root in ("src", "plugin", "tests", "examples", "models", "tools"):
    base = tree / root
    if not base.exists():
      continue
    for p in base.rglob("*"):
      if p.is_file() and str(p.relative_to(tree)) not in keep:
        p.unlink()
  return tree


def configure(tree, build, log):
  if not (build / "build.ninja").exists():
    cmd = ["cmake", "-S", tree, "-B", build, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
           "-DMJTETHER_BENCHMARKS=OFF"]
    if shutil.which("ccache"):
      cmd.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
    status, out = run(cmd, log=log)
    if status != 0:
      sys.exit(f"cmake failed:\n{out}")


def build_tree(build, jobs, log):
  status, out = run(["cmake", "--build", build, f"-j{jobs}"], log=log)
  return status == 0, out


def run_suite(build, jobs, log, first_only, regex=None):
  """Runs the fast suite; returns the names of the tests that failed (empty: all passed).
  With first_only, ctest stops starting tests after the first failure (tests that failed in the
  previous run go first, so a mutant like the last one is caught in seconds)."""
  failed_log = build / "Testing" / "Temporary" / "LastTestsFailed.log"
  cmd = ["ctest", "--test-dir", build, f"-j{jobs}", "-LE", FAST_EXCLUDE_LABELS, "-E",
         FAST_EXCLUDE_NAMES, "--timeout", str(TEST_TIMEOUT)]
  if regex:
    cmd += ["-R", regex]
  if first_only:
    cmd.append("--stop-on-failure")
  status, out = run(cmd, log=log)
  if status == 0 and failed_log.exists():
    failed_log.unlink()  # ctest leaves the previous run's list when every test passed
  failed = []
  if failed_log.exists():
    for line in failed_log.read_text().splitlines():
      failed.append(line.split(":", 1)[1] if ":" in line else line)
  if status != 0 and not failed:
    failed = ["(ctest failed without a failing test: see the log)"]
  if status == 0 and regex and "No tests were found" in out:
    failed = []  # a stale `first` regex: the whole suite decides (the log says so)
  return failed


def fast_suite_tests(build):
  """The names of the fast suite's tests in a configured build directory (None without one)."""
  if not (build / "CTestTestfile.cmake").exists():
    return None
  status, out = run(["ctest", "--test-dir", build, "-N", "-LE", FAST_EXCLUDE_LABELS, "-E",
                     FAST_EXCLUDE_NAMES])
  if status != 0:
    return None
  return [m.group(1) for m in re.finditer(r"^\s*Test\s+#\d+: (\S+)", out, re.M)]


def check_pattern(tree, e):
  """The number of occurrences of the entry's pattern in its file (or -1 if there is none)."""
  path = tree / e["file"]
  if not path.exists():
    return -1
  return path.read_text().count(e["find"])


def main():
  ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
  ap.add_argument("--catalogue", default=str(REPO / "tools" / "mutations.cfg"))
  ap.add_argument("--scratch", default=os.path.join(tempfile.gettempdir(), "mjtether-mutation"),
                  help="scratch directory (tree copy and build), kept between runs")
  ap.add_argument("--only", help="comma-separated entry ids")
  ap.add_argument("--sample", action="store_true", help="only entries marked sample = yes")
  ap.add_argument("--list", action="store_true", help="list entries and check patterns only")
  ap.add_argument("--jobs", type=int, default=2)
  ap.add_argument("--all-tests", action="store_true",
                  help="run the whole fast suite on each mutant and list every test that "
                       "catches it (default: stop at the first failing test)")
  ap.add_argument("--report", help="also write the results as a Markdown table to this file")
  ap.add_argument("--in-place", action="store_true",
                  help="plant each mutant in the repository itself and build in --build "
                       "(for a disposable clone; refuses files with uncommitted changes)")
  ap.add_argument("--build", default=str(REPO / "build"),
                  help="with --in-place: the configured build directory (default: build/)")
  ap.add_argument("--no-baseline", action="store_true",
                  help="build the unmutated tree but do not run its suite (when the caller "
                       "has just run it, as .ci/run has)")
  args = ap.parse_args()
  # A SIGTERM (a CI time-out, kill) unwinds like an exception, so that the `finally` below
  # restores a mutated file (in place: the repository's own).
  signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))

  entries = load_catalogue(args.catalogue)
  ids = [e["id"] for e in entries]
  if len(set(ids)) != len(ids):
    sys.exit("duplicate entry ids in the catalogue")
  if args.only:
    wanted = args.only.split(",")
    unknown = [w for w in wanted if w not in ids]
    if unknown:
      print(f"unknown entries: {', '.join(unknown)}", file=sys.stderr)
      return 2
    by_id = {e["id"]: e for e in entries}
    entries = [by_id[w] for w in wanted]  # in the order given
  if args.sample:
    entries = [e for e in entries if e["sample"]]

  if args.list:
    # With a configured build: each entry's `first` must name a test of the fast suite. One
    # that names only excluded tests (a valgrind, long or scene_fuzz label, the renderer's)
    # runs nothing first, and the mutant is then judged by a suite that never runs the test
    # meant to catch it (session 34's note).
    fast = fast_suite_tests(pathlib.Path(args.build).resolve())
    bad = 0
    for e in entries:
      n = check_pattern(REPO, e)
      why = "" if n == 1 else f"  (pattern found {max(n, 0)} times)"
      if not why and fast is not None and e["first"] and \
          not any(re.search(e["first"], t) for t in fast):
        why = "  (`first` names no test of the fast suite)"
      bad += bool(why)
      flags = ("S" if e["sample"] else " ") + ("E" if e["equivalent"] else " ")
      print(f"{'ERR' if why else 'ok '} {flags} {e['id']:34s} {e['file']}{why}")
    checked = "" if fast is not None else " (`first` not checked: no configured build)"
    print(f"{len(entries)} entries, {bad} with a pattern that does not occur exactly once or a "
          f"`first` outside the fast suite{checked}")
    return 1 if bad else 0

  scratch = pathlib.Path(args.scratch).resolve()
  if scratch == REPO or REPO in scratch.parents:
    print("the scratch directory must be outside the repository", file=sys.stderr)
    return 2
  scratch.mkdir(parents=True, exist_ok=True)
  log = open(scratch / "mutate.log", "w")
  if args.in_place:
    tree, build = REPO, pathlib.Path(args.build).resolve()
    if not (build / "CMakeCache.txt").exists():
      print(f"--in-place: {build} is not a configured build directory", file=sys.stderr)
      return 2
    dirty = subprocess.run(["git", "status", "--porcelain", "--"] +
                           sorted({e["file"] for e in entries}), cwd=REPO,
                           stdout=subprocess.PIPE, text=True, check=True).stdout.strip()
    if dirty:
      print(f"--in-place: these files have uncommitted changes, which a mutant would "
            f"overwrite:\n{dirty}", file=sys.stderr)
      return 2
    print(f"in place: {REPO}, build {build} (log: {scratch / 'mutate.log'})", flush=True)
  else:
    print(f"scratch tree and build: {scratch} (log: {scratch / 'mutate.log'})", flush=True)
    tree = sync_tree(scratch)
    build = scratch / "build"
    configure(tree, build, log)
  t0 = time.time()
  ok, out = build_tree(build, args.jobs, log)
  if not ok:
    print(f"the unmutated tree does not build:\n{out[-3000:]}", file=sys.stderr)
    return 2
  if not args.no_baseline:
    failed = run_suite(build, args.jobs, log, False)
    if failed:
      print(f"the unmutated suite fails: {', '.join(failed)}", file=sys.stderr)
      return 2
  print(f"baseline: builds{'' if args.no_baseline else ' and passes'} "
        f"({time.time() - t0:.0f} s)", flush=True)

  results = []
  for k, e in enumerate(entries, 1):
    path = tree / e["file"]
    n = check_pattern(tree, e)
    t1 = time.time()
    if n != 1:
      r = {"status": "error",
           "detail": f"pattern found {max(n, 0)} times in {e['file']} (must be exactly once)"}
    else:
      original = path.read_text()
      path.write_text(original.replace(e["find"], e["replace"], 1))
      try:
        log.write(f"\n=== {e['id']}\n")
        built, out = build_tree(build, args.jobs, log)
        if not built:
          r = {"status": "error", "detail": "the mutant does not compile"}
        else:
          failed = []
          if e["first"] and not args.all_tests:
            failed = run_suite(build, args.jobs, log, True, e["first"])
          if not failed:
            failed = run_suite(build, args.jobs, log, not args.all_tests)
          if failed:
            r = {"status": "caught", "detail": ", ".join(failed)}
          else:
            r = {"status": "survived", "detail": ""}
      finally:
        path.write_text(original)  # new time stamp: the next build recompiles it (ccache hit)
    r["seconds"] = time.time() - t1
    r.update(e)
    results.append(r)
    shown = r["status"] + (" (equivalent)" if e["equivalent"] else "")
    detail = r["detail"] if len(r["detail"]) < 200 else r["detail"][:200] + " ..."
    print(f"[{k}/{len(entries)}] {e['id']}: {shown} in {r['seconds']:.0f} s  {detail}",
          flush=True)

  # Leave the build matching the repository again (the last file was restored): in place, the
  # caller's build directory must not keep a mutant's objects.
  if args.in_place:
    ok, out = build_tree(build, args.jobs, log)
    if not ok:
      print(f"rebuilding the restored tree failed:\n{out[-3000:]}", file=sys.stderr)
      return 2
  scored = [r for r in results if not r["equivalent"] and r["status"] != "error"]
  caught = sum(r["status"] == "caught" for r in scored)
  survived = [r for r in scored if r["status"] == "survived"]
  errors = [r for r in results if r["status"] == "error"]
  equivalent = [r for r in results if r["equivalent"]]
  eq_caught = [r for r in equivalent if r["status"] == "caught"]
  score = 100.0 * caught / len(scored) if scored else 0.0
  summary = (f"{len(results)} mutants: {caught} caught, {len(survived)} survived, "
             f"{len(errors)} errors, {len(equivalent)} marked equivalent; "
             f"score {caught}/{len(scored)} = {score:.1f}%")
  print(summary)
  for r in survived:
    print(f"SURVIVED {r['id']}: {r['file']}: {r['breaks']}")
  for r in errors:
    print(f"ERROR {r['id']}: {r['detail']}")
  for r in eq_caught:
    print(f"NOTE {r['id']} is marked equivalent but a test failed: {r['detail']}")

  if args.report:
    with open(args.report, "w") as f:
      f.write(f"{summary}\n\n| entry | file | breaks | result | caught by |\n"
              "|---|---|---|---|---|\n")
      for r in results:
        status = r["status"] + (" (equivalent)" if r["equivalent"] else "")
        by = r["detail"].replace("|", "\\|")
        f.write(f"| {r['id']} | {r['file']} | {r['breaks']} | {status} | {by} |\n")
  return 1 if survived or errors else 0


if __name__ == "__main__":
  sys.exit(main())
