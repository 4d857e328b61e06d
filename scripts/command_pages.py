#!/usr/bin/env python3
"""The reference page of every `fivebar` command, docs/commands/<command>.md, from the executable
and the command's source: synopsis (the source's first comment lines), what it does (`fivebar
--help`), options (`fivebar <command> --help`), output files (the names the command writes), exit
codes. Pages are generated, not written by hand, so they stay true: the test `apps.command_pages`
runs `--check`, which also checks that README.md's command table names every command and links
its page.

Usage: command_pages.py FIVEBAR [--check]     (FIVEBAR: build/release/apps/fivebar)
"""
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAGES = ROOT / "docs" / "commands"

EXIT_CODES = """| status | meaning |
|---|---|
| 0 | done: the outputs are written and the run's own checks passed |
| 1 | command line not understood (unknown option, missing argument): one line on stderr |
| 2 | bad input (scene, log, motion or tasks file, option value): one line `fivebar: error: <file>: <key>: <reason>` on stderr, no output written |
| 3 | the numerics failed on valid input, or a run's own checks failed (its outputs stay for inspection) |
"""

# outputs the source does not list by name
MORE_OUTPUTS = {"optimize": ["`<task>/`: one folder per solved task (its trajectory, the baseline's, "
                             "figures)"]}


def help_text(fivebar, *args):
    return subprocess.run([fivebar, *args, "--help"], capture_output=True, text=True,
                          check=True).stdout.rstrip() + "\n"


def commands(fivebar):
    """{command: one-line summary} from `fivebar --help`."""
    out, listing = {}, False
    for line in help_text(fivebar).splitlines():
        if line.startswith("Subcommands:"):
            listing = True
        elif listing and line.strip():
            name, summary = line.split(None, 1)
            out[name] = summary.strip()
    return out


def source_of(command):
    return ROOT / "apps" / f"cmd_{command.replace('-', '_')}.cc"


def synopsis(source):
    """The first comment lines of the source naming the command line."""
    lines = []
    for line in source.read_text().splitlines():
        if not line.startswith("// "):
            break
        text = line[3:]
        if text.startswith("fivebar ") or (lines and text.startswith("  ")):
            lines.append(text.strip() if not lines else "    " + text.strip())
        elif lines:
            break
    return "\n".join(lines)


def outputs(source):
    """File names the command writes: the lists given to OutputDir (or kOutputs)."""
    text = source.read_text()
    names = []
    lists = re.findall(r"kOutputs\s*=\s*\{(.*?)\};", text, re.S)
    lists += re.findall(r"OutputDir \w+\([^,]+,\s*\{(.*?)\}\)", text, re.S)
    for block in lists:
        for name in re.findall(r'"([^"]+)"', block):
            if name not in names:
                names.append(name)
    return names


def anchor(command):
    """The section of docs/outputs.md about the command, when there is one."""
    text = (ROOT / "docs" / "outputs.md").read_text()
    return f"../outputs.md#fivebar-{command}" if f"## `fivebar {command}`" in text else None


def page(fivebar, command, summary):
    source = source_of(command)
    files = outputs(source)
    link = anchor(command)
    out = [f"# fivebar {command}", "", summary[0].upper() + summary[1:] + ".", "",
           "## Synopsis", "", "```", synopsis(source), "```", "",
           "## Options", "", f"As printed by `fivebar {command} --help`:", "", "```",
           help_text(fivebar, command).rstrip(), "```", ""]
    out += ["## Outputs", ""]
    if files:
        out += ["The files it may write into `--out DIR` (a previous run's copies are removed "
                "first; nothing is written when the input is bad):", ""]
        out += [f"- `{name}`" for name in files]
        out += [f"- {more}" for more in MORE_OUTPUTS.get(command, [])]
    elif command == "synth-log":
        out += ["The log file named by `--out` (format: [formats.md](../formats.md#torque-logs)), "
                "with the true parameters in its header."]
    else:
        out += ["Files in `--out DIR`; see the link below."]
    if link:
        out += ["", f"Their columns and fields: [outputs.md]({link})."]
    out += ["", "## Exit status", "", EXIT_CODES.rstrip(), ""]
    return "\n".join(out) + "\n"


def readme_problems(names):
    """Commands missing from README.md's command table, or whose page it does not link."""
    table = [line for line in (ROOT / "README.md").read_text().splitlines()
             if line.startswith("| [`fivebar ") or line.startswith("| `fivebar ")]
    problems = []
    for name in names:
        rows = [r for r in table if re.match(rf"\| \[?`fivebar {re.escape(name)}[ `]", r)]
        if not rows:
            problems.append(f"README.md: command table: no row for `fivebar {name}`")
        elif f"docs/commands/{name}.md" not in rows[0]:
            problems.append(f"README.md: command table: `fivebar {name}` does not link "
                            f"docs/commands/{name}.md")
    return problems


def main():
    fivebar, check = sys.argv[1], "--check" in sys.argv[2:]
    listed = commands(fivebar)
    problems = []
    PAGES.mkdir(parents=True, exist_ok=True)
    for name, summary in listed.items():
        path = PAGES / f"{name}.md"
        text = page(fivebar, name, summary)
        if not check:
            path.write_text(text)
        elif not path.exists() or path.read_text() != text:
            problems.append(f"{path.relative_to(ROOT)}: out of date (run scripts/command_pages.py "
                            f"{fivebar})")
    for path in sorted(PAGES.glob("*.md")):
        if path.stem not in listed:
            problems.append(f"{path.relative_to(ROOT)}: no such command")
    problems += readme_problems(listed)
    for p in problems:
        print(p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
