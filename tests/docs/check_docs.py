#!/usr/bin/env python3
"""Checks visproxy's documentation against the tree and the built tools (stdlib only).

    check_docs.py --source SRC --visproxy BIN [--python PY] [--python-path DIR]
                  [--mesh-dir DIR] [--update] [--no-run] [--keep] [--verbose]

What it checks (each problem is one line, FILE:LINE: what is wrong; exit code 1 if any):

 1. README.md holds at most 12 000 characters: it is the front door, the rest lives in
    the documents it links to.
 2. Links. Every Markdown file under SRC (build/, .git/ and hidden folders skipped):
    every relative link or image ([text](path), [text](path#anchor), [name]: path,
    <a href>, <img src>) names an existing file or folder, and every #anchor an existing
    heading of the target Markdown file (GitHub's slugs: lowercase, punctuation other
    than - and _ dropped, spaces to -, repeats numbered -1, -2, ...) or an explicit
    <a name>/id. A code span that is a path into the tree (`lib/...`, `apps/...`,
    `tests/...`, `cmake/...`, `data/...`) must name an existing file or folder too;
    path parts in capitals (`lib/visproxy/MODULE/NAME.h`) are placeholders and skipped.
 3. Generated option listings. In apps/visproxy/README.md each block

        <!-- visproxy build --help -->
        ```text
        ...
        ```
        <!-- end -->

    must hold exactly what the built binary prints for that command (trailing spaces
    and trailing blank lines aside), and there must be one for `visproxy --help`, every
    subcommand it lists, and every subcommand of those (`visproxy generate room --help`).
    `--update` rewrites the blocks from the binary instead of failing: run it after a
    change to a --help string or to the proxy-method table, and commit the result.
 4. Examples run. In README.md, apps/visproxy/README.md, apps/bench/README.md,
    lib/README.md and lib/python/README.md:
      - every line of a ```sh block that starts with `visproxy ` is run with `visproxy`
        replaced by BIN (a trailing `\\` continues the line; quotes and `# comments` as
        in sh, without expansion). It must exit 0, or N when the line ends with the
        comment `# exits N`. Other lines of a ```sh block (sh cmake/bootstrap.sh ...,
        cmake, c++) are not run;
      - every ```python block is run as a script by PY with PYTHONPATH=DIR (the built
        module) and must exit 0.
    Each document runs in order, in a fresh temporary folder of its own, so an example
    may use what an earlier one in the same document wrote. The folder holds `data` (a
    link to SRC/data), `build/release/meshes` (a link to --mesh-dir, the libcgal-demo
    meshes the build extracts) and `build/release/assimp-testmodels` (beside it, Debian's
    assimp-testmodels the build unpacks), so the examples read as they run from the repository
    root after `sh cmake/bootstrap.sh demo`. XDG_CACHE_HOME points into the folder: every
    run builds its proxies afresh.
    Examples that must not run in a test (package installs, cluster submissions, long
    benchmarks and renders) go in ```console or ```text blocks, which are not run.
    `--no-run` skips this part.

ctest runs it as Docs.LinksAndCommands (tests/CMakeLists.txt).
"""
import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.parse

README_LIMIT = 12000
CLI_REFERENCE = "apps/visproxy/README.md"
RUN_DOCS = ["README.md", CLI_REFERENCE, "apps/bench/README.md", "lib/README.md", "lib/python/README.md"]
SKIP_DIRS = {"build", ".git", "node_modules", "__pycache__"}
TREE_PATH = re.compile(r"^(?:lib|apps|tests|cmake|data)/[\w./+-]*$")
FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})\s*([^`]*)$")
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]*)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE = re.compile(r"^ {0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+\"[^\"]*\")?\s*$")
HTML_LINK = re.compile(r"<(?:a|img)\b[^>]*\b(?:href|src)\s*=\s*\"([^\"]*)\"", re.IGNORECASE)
HTML_ANCHOR = re.compile(r"<[a-z]+\b[^>]*\b(?:name|id)\s*=\s*\"([^\"]*)\"", re.IGNORECASE)
CODE_SPAN = re.compile(r"(`+)(.+?)\1")
HEADING = re.compile(r"^ {0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
HELP_MARKER = re.compile(r"^<!--\s*(visproxy\b.*?--help)\s*-->\s*$")
END_MARKER = re.compile(r"^<!--\s*end\s*-->\s*$")
EXITS = re.compile(r"#\s*exits\s+(\d+)\s*$")

problems = []


def problem(path, line, message):
    problems.append(f"{path}:{line}: {message}")


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def markdown_files(source):
    found = []
    for root, dirs, files in os.walk(source):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and not d.startswith("."))
        found += [os.path.join(root, f) for f in sorted(files) if f.endswith(".md")]
    return found


def lines_outside_code(text):
    """(line number, line) of every line outside fenced code blocks."""
    fence = None
    for number, line in enumerate(text.split("\n"), 1):
        match = FENCE.match(line)
        if fence is None:
            if match:
                fence = match.group(1)
                continue
            yield number, line
        elif match and match.group(1)[0] == fence[0] and len(match.group(1)) >= len(fence) and not match.group(2).strip():
            fence = None


def fenced_blocks(text):
    """(info string, first line number of the content, content lines) of every fenced block."""
    blocks, fence, info, start, body = [], None, "", 0, []
    for number, line in enumerate(text.split("\n"), 1):
        match = FENCE.match(line)
        if fence is None:
            if match:
                fence, info, start, body = match.group(1), match.group(2).strip(), number + 1, []
        elif match and match.group(1)[0] == fence[0] and len(match.group(1)) >= len(fence) and not match.group(2).strip():
            blocks.append((info, start, body))
            fence = None
        else:
            body.append(line)
    return blocks


def slug(heading):
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links and images: their text
    text = re.sub(r"<[^>]+>", "", text)
    text = text.replace("`", "").replace("*", "").lower()
    text = "".join(c for c in text if c.isalnum() or c in " -_")
    return text.replace(" ", "-")


anchor_cache = {}


def anchors(path):
    if path not in anchor_cache:
        found, seen = set(), {}
        for _, line in lines_outside_code(read(path)):
            match = HEADING.match(line)
            if match:
                base = slug(match.group(2))
                count = seen.get(base, 0)
                seen[base] = count + 1
                found.add(base if count == 0 else f"{base}-{count}")
            found.update(HTML_ANCHOR.findall(line))
        anchor_cache[path] = found
    return anchor_cache[path]


def check_link(source, path, number, target):
    if not target or re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) or target.startswith("//"):
        return
    file_part, _, anchor = target.partition("#")
    file_part = urllib.parse.unquote(file_part)
    if file_part.startswith("/"):
        resolved = os.path.join(source, file_part.lstrip("/"))
    elif file_part:
        resolved = os.path.normpath(os.path.join(os.path.dirname(path), file_part))
    else:
        resolved = path
    if not os.path.exists(resolved):
        problem(os.path.relpath(path, source), number, f"link to {target}: no file {os.path.relpath(resolved, source)}")
        return
    if anchor and resolved.endswith(".md") and urllib.parse.unquote(anchor) not in anchors(resolved):
        problem(os.path.relpath(path, source), number,
                f"link to {target}: {os.path.relpath(resolved, source)} has no heading #{anchor}")


def check_tree_path(source, path, number, span):
    span = span.strip()
    if not TREE_PATH.match(span) or ".." in span:
        return
    parts = [p for p in span.split("/") if p]
    if any(re.fullmatch(r"[A-Z][A-Z0-9_]*", p.split(".")[0]) for p in parts):
        return  # a placeholder: lib/visproxy/MODULE/NAME.h
    if not os.path.exists(os.path.join(source, span)):
        problem(os.path.relpath(path, source), number, f"`{span}` names no file or folder in the tree")


def check_links(source):
    files = markdown_files(source)
    for path in files:
        for number, line in lines_outside_code(read(path)):
            for span in CODE_SPAN.findall(line):
                check_tree_path(source, path, number, span[1])
            plain = CODE_SPAN.sub("", line)
            targets = LINK.findall(plain) + HTML_LINK.findall(plain)
            match = REFERENCE.match(plain)
            if match:
                targets.append(match.group(1))
            for target in targets:
                check_link(source, path, number, target)
    return len(files)


def run_help(visproxy, command):
    argv = [visproxy] + shlex.split(command)[1:]
    run = subprocess.run(argv, capture_output=True, text=True, timeout=60)
    if run.returncode != 0:
        raise RuntimeError(f"`{command}` exited {run.returncode}: {run.stderr.strip()[:200]}")
    return normalise(run.stdout.split("\n"))


def normalise(lines):
    lines = [line.rstrip() for line in lines]
    while lines and not lines[-1]:
        lines.pop()
    return lines


def subcommands(help_lines):
    names, inside = [], False
    for line in help_lines:
        if line.strip() == "Subcommands:":
            inside = True
        elif inside:
            match = re.match(r"^  ([A-Za-z][\w-]*)(?:\s{2,}|$)", line)
            if match:
                names.append(match.group(1))
            elif not line.strip():
                inside = False
    return names


def check_help_blocks(source, visproxy, update):
    path = os.path.join(source, CLI_REFERENCE)
    if not os.path.exists(path):
        problem(CLI_REFERENCE, 1, "missing")
        return 0
    lines = read(path).split("\n")
    found, changed, index = {}, False, 0
    while index < len(lines):
        match = HELP_MARKER.match(lines[index])
        if not match:
            index += 1
            continue
        command, marker = " ".join(match.group(1).split()), index + 1
        open_fence = index + 1
        if open_fence >= len(lines) or not re.match(r"^```text\s*$", lines[open_fence]):
            problem(CLI_REFERENCE, marker, f"`{command}`: the marker must be followed by a ```text block")
            index += 1
            continue
        close = open_fence + 1
        while close < len(lines) and lines[close].rstrip() != "```":
            close += 1
        if close + 1 >= len(lines) or not END_MARKER.match(lines[close + 1]):
            problem(CLI_REFERENCE, marker, f"`{command}`: the block must end with ``` and <!-- end -->")
            index = close + 1
            continue
        if command in found:
            problem(CLI_REFERENCE, marker, f"`{command}`: a second block (the first is at line {found[command]})")
        found[command] = marker
        try:
            expected = run_help(visproxy, command)
        except (RuntimeError, OSError, subprocess.TimeoutExpired) as e:
            problem(CLI_REFERENCE, marker, str(e))
            index = close + 2
            continue
        if normalise(lines[open_fence + 1:close]) != expected:
            if update:
                lines[open_fence + 1:close] = expected
                close = open_fence + 1 + len(expected)
                changed = True
            else:
                current = normalise(lines[open_fence + 1:close])
                first = next((i for i in range(max(len(current), len(expected)))
                              if i >= len(current) or i >= len(expected) or current[i] != expected[i]), 0)
                problem(CLI_REFERENCE, open_fence + 2 + first,
                        f"`{command}` prints something else here now (run tests/docs/check_docs.py --update)")
        index = close + 2
    # Every command and subcommand has its block.
    try:
        required = ["visproxy --help"]
        for name in subcommands(run_help(visproxy, "visproxy --help")):
            required.append(f"visproxy {name} --help")
            for sub in subcommands(run_help(visproxy, f"visproxy {name} --help")):
                required.append(f"visproxy {name} {sub} --help")
        for command in required:
            if command not in found:
                problem(CLI_REFERENCE, 1, f"no generated block <!-- {command} --> for a command the binary has")
    except (RuntimeError, OSError, subprocess.TimeoutExpired) as e:
        problem(CLI_REFERENCE, 1, str(e))
    if changed:
        with open(path, "w", encoding="utf-8") as f:
            f.write("\n".join(lines))
        print(f"check_docs: rewrote the --help blocks of {CLI_REFERENCE} from {visproxy}")
    return len(found)


def examples(text):
    """('sh', line number, command line, expected code) and ('python', line number, script, 0), in order."""
    found = []
    for info, start, body in fenced_blocks(text):
        language = info.split()[0] if info else ""
        if language == "sh":
            pending, pending_line = "", 0
            for offset, line in enumerate(body):
                stripped = line.strip()
                if not pending:
                    pending_line = start + offset
                pending += stripped
                if pending.endswith("\\"):
                    pending = pending[:-1] + " "
                    continue
                if pending.startswith("visproxy "):
                    match = EXITS.search(pending)
                    found.append(("sh", pending_line, pending, int(match.group(1)) if match else 0))
                pending = ""
        elif language in ("python", "py"):
            found.append(("python", start, "\n".join(body) + "\n", 0))
    return found


def prepare_folder(source, visproxy, mesh_dir):
    folder = tempfile.mkdtemp(prefix="visproxy-docs-")
    os.symlink(os.path.join(source, "data"), os.path.join(folder, "data"))
    if mesh_dir and os.path.isdir(mesh_dir):
        os.makedirs(os.path.join(folder, "build", "release"))
        os.symlink(mesh_dir, os.path.join(folder, "build", "release", "meshes"))
        # Debian's assimp-testmodels, which the build unpacks beside the meshes.
        models = os.path.join(os.path.dirname(mesh_dir), "assimp-testmodels")
        if os.path.isdir(models):
            os.symlink(models, os.path.join(folder, "build", "release", "assimp-testmodels"))
    os.makedirs(os.path.join(folder, ".docs", "bin"))
    os.symlink(visproxy, os.path.join(folder, ".docs", "bin", "visproxy"))
    return folder


def run_examples(source, visproxy, python, python_path, mesh_dir, keep, verbose):
    count, started = 0, time.monotonic()
    for doc in RUN_DOCS:
        path = os.path.join(source, doc)
        if not os.path.exists(path):
            continue
        todo = examples(read(path))
        if not todo:
            continue
        folder = prepare_folder(source, visproxy, mesh_dir)
        env = dict(os.environ)
        env.update({"PATH": os.path.join(folder, ".docs", "bin") + os.pathsep + env.get("PATH", ""),
                    "XDG_CACHE_HOME": os.path.join(folder, ".docs", "cache"),
                    "PYTHONDONTWRITEBYTECODE": "1"})
        if mesh_dir:
            env["VISPROXY_MESH_DIR"] = mesh_dir
        if python_path:
            env["PYTHONPATH"] = python_path + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        for kind, line, code, expected in todo:
            count += 1
            if kind == "sh":
                try:
                    argv = shlex.split(code, comments=True)
                except ValueError as e:
                    problem(doc, line, f"`{code}`: {e}")
                    continue
                argv[0] = visproxy
                shown = code
            else:
                script = os.path.join(folder, ".docs", f"example-{line}.py")
                with open(script, "w", encoding="utf-8") as f:
                    f.write(code)
                argv, shown = [python, script], f"python block at line {line}"
            begin = time.monotonic()
            try:
                run = subprocess.run(argv, cwd=folder, env=env, capture_output=True, text=True, timeout=600)
                code_returned, output = run.returncode, (run.stderr.strip() or run.stdout.strip())
            except (OSError, subprocess.TimeoutExpired) as e:
                code_returned, output = None, str(e)
            if verbose:
                print(f"  {time.monotonic() - begin:6.2f} s  {doc}:{line}: {shown[:100]}")
            if code_returned != expected:
                last = output.split("\n")[-1][:300] if output else "(no output)"
                problem(doc, line, f"`{shown[:120]}` exited {code_returned}, expected {expected}: {last}")
        if keep:
            print(f"check_docs: {doc}'s examples ran in {folder}")
        else:
            shutil.rmtree(folder, ignore_errors=True)
    return count, time.monotonic() - started


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source", required=True, help="the repository root")
    parser.add_argument("--visproxy", required=True, help="the built visproxy binary")
    parser.add_argument("--python", default=sys.executable, help="interpreter for the ```python examples")
    parser.add_argument("--python-path", default="", help="folder of the built Python module")
    parser.add_argument("--mesh-dir", default="", help="the extracted libcgal-demo meshes [default: SRC/build/release/meshes]")
    parser.add_argument("--update", action="store_true", help="rewrite the generated --help blocks instead of failing")
    parser.add_argument("--no-run", action="store_true", help="do not run the examples")
    parser.add_argument("--keep", action="store_true", help="keep the examples' temporary folders")
    parser.add_argument("--verbose", action="store_true", help="print each example with its time")
    args = parser.parse_args()
    source = os.path.abspath(args.source)
    visproxy = os.path.abspath(args.visproxy)
    mesh_dir = os.path.abspath(args.mesh_dir or os.path.join(source, "build", "release", "meshes"))
    python_path = os.path.abspath(args.python_path) if args.python_path else ""

    readme = os.path.join(source, "README.md")
    size = len(read(readme))
    if size > README_LIMIT:
        problem("README.md", 1, f"{size} characters, more than {README_LIMIT}: move detail into the documents it links to")
    documents = check_links(source)
    if not os.access(visproxy, os.X_OK):
        problem(args.visproxy, 1, "not an executable: build the visproxy target")
        blocks, examples_run, seconds = 0, 0, 0.0
    else:
        blocks = check_help_blocks(source, visproxy, args.update)
        examples_run, seconds = (0, 0.0) if args.no_run else run_examples(
            source, visproxy, args.python, python_path, mesh_dir, args.keep, args.verbose)
    for line in problems:
        print(line)
    summary = (f"README.md {size} characters; {documents} Markdown files' links; {blocks} --help blocks; "
               f"{examples_run} examples in {seconds:.1f} s")
    if problems:
        print(f"check_docs: {len(problems)} problem(s). {summary}")
        return 1
    print(f"check_docs: OK. {summary}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
