#!/usr/bin/env python3
"""Writes docs/api.md, the API reference, from the public headers.

The headers are the reference: each declaration's comment says what it does,
its statuses, ownership and thread safety (docs/style.md, item 11). This
script lays them out as one page -- the headers in the umbrella header's
order, each declaration under its names with its comment, experimental ones
marked -- so that the page cannot say anything the headers do not.

    python3 scripts/api_doc.py [-o docs/api.md]    (make api-doc)
    python3 scripts/api_doc.py --check docs/api.md  (tests/api_doc.sh)

It fails, naming file:line, on an exported function (LL_API) without a
comment. Python 3 standard library only.
"""

import argparse
import difflib
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UMBRELLA = "include/layerlab.h"
HEADERS = "include/layerlab"

GUARD = re.compile(r"^#\s*(ifndef|define)\s+LAYERLAB_\w+_H\b")
EXPERIMENTAL_IF = re.compile(r"^#\s*(ifdef\s+LL_EXPERIMENTAL\b|if\s+defined\(LL_EXPERIMENTAL\))")
CPLUSPLUS_IF = re.compile(r"^#\s*ifdef\s+__cplusplus\b")
CONDITIONAL_IF = re.compile(r"^#\s*if")
CONDITIONAL_END = re.compile(r"^#\s*endif\b")
CONDITIONAL_ELSE = re.compile(r"^#\s*(else|elif)\b")
SECTION_RULE = re.compile(r"^-{3,}\s*(.*)$")
FUNCTION = re.compile(r"^LL_API\b[^;(]*?\b(\w+)\s*\(", re.S | re.M)
TYPEDEF_NAME = re.compile(r"\}\s*(\w+)\s*;|typedef\s+[^;{}()]*?\b(\w+)\s*;|typedef\s+[^;{}]*?\(\s*\*\s*(\w+)\)")
MACRO = re.compile(r"^#\s*define\s+(\w+)", re.M)


class Entry:
    """A comment and the declarations under it, as one unit of the page."""

    def __init__(self, comment, code, experimental, line):
        self.comment = comment        # list of lines, or None
        self.code = code              # list of lines (may be empty: prose)
        self.experimental = experimental
        self.line = line              # 1-based line of the entry's start


def comment_text(lines):
    """The text of a /* ... */ block without its delimiters and leaders."""
    out = []
    for i, raw in enumerate(lines):
        s = raw.rstrip()
        if i == 0:
            s = re.sub(r"^\s*/\*+", "", s)
        if s.endswith("*/"):
            s = s[:-2].rstrip()
        if i > 0:
            s = re.sub(r"^\s*\*(?!/)", "", s, count=1)
        if s.startswith(" "):
            s = s[1:]
        out.append(s)
    while out and not out[0].strip():
        out.pop(0)
    while out and not out[-1].strip():
        out.pop()
    return out


def braces(line):
    """Braces opened minus closed on a line of code, comments left out."""
    code = re.sub(r"/\*.*?(\*/|$)", "", line)
    return code.count("{") - code.count("}")


def parse(path):
    """The header's top comment and its entries."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    stack = []          # kinds of the open conditionals: guard, cplusplus, experimental, code
    entries = []
    top = None
    comment = None
    comment_line = 0
    code = []
    code_line = 0

    def experimental():
        return "experimental" in stack

    def flush():
        nonlocal comment, code
        if comment is not None or code:
            entries.append(Entry(comment, code, experimental(), comment_line if comment else code_line))
        comment, code = None, []

    depth = 0           # open braces of the code being collected
    i = 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if depth > 0:
            # Inside a struct or enum everything is its code, comments too.
            code.append(line.rstrip())
            depth += braces(line)
            i += 1
            continue
        if line.startswith("/*") and not code:
            # A comment opening a line (a trailing one belongs to its code).
            start = i
            while "*/" not in lines[i]:
                i += 1
            block = comment_text(lines[start:i + 1])
            if top is None and not entries and comment is None:
                top = block
            else:
                if comment is not None:
                    flush()
                comment, comment_line = block, start + 1
            i += 1
            continue
        if line.startswith("/*") and code:
            flush()
            continue
        if not stripped:
            flush()
            i += 1
            continue
        if stripped.startswith("#"):
            if GUARD.match(stripped) or stripped.startswith("#include"):
                if stripped.startswith("#ifndef"):
                    stack.append("guard")
                i += 1
                continue
            if EXPERIMENTAL_IF.match(stripped):
                flush()
                stack.append("experimental")
                i += 1
                continue
            if CPLUSPLUS_IF.match(stripped):
                stack.append("cplusplus")
                i += 1
                continue
            if CONDITIONAL_IF.match(stripped):
                stack.append("code")
            elif CONDITIONAL_END.match(stripped):
                kind = stack.pop() if stack else "code"
                if kind != "code":
                    flush()
                    i += 1
                    continue
            elif CONDITIONAL_ELSE.match(stripped) and stack and stack[-1] != "code":
                i += 1
                continue
        if stack and stack[-1] == "cplusplus":
            i += 1
            continue
        if not code:
            code_line = i + 1
        code.append(line.rstrip())
        depth += braces(line)
        i += 1
    flush()
    return top or [], entries


def names_of(code):
    text = "\n".join(code)
    functions = FUNCTION.findall(text)
    if functions:
        return functions, "function"
    types = [next(n for n in m if n) for m in TYPEDEF_NAME.findall(text)]
    macros = MACRO.findall(text)
    names = []
    for n in types + macros:
        if n not in names:
            names.append(n)
    return names, "other"


def header_order():
    """The headers in the umbrella header's order, then any it misses."""
    with open(os.path.join(ROOT, UMBRELLA), encoding="utf-8") as f:
        listed = re.findall(r'#include\s+"layerlab/(\w+\.h)"', f.read())
    present = sorted(n for n in os.listdir(os.path.join(ROOT, HEADERS)) if n.endswith(".h"))
    return [n for n in listed if n in present] + [n for n in present if n not in listed]


def fence(lines, lang=""):
    return ["```" + lang] + lines + ["```"]


def render():
    problems = []
    headers = []
    for name in header_order():
        rel = HEADERS + "/" + name
        top, entries = parse(os.path.join(ROOT, rel))
        headers.append((name, rel, top, entries))
        for e in entries:
            names, kind = names_of(e.code)
            if kind == "function" and not e.comment:
                problems.append("%s:%d: %s has no comment" % (rel, e.line, ", ".join(names)))

    out = []
    out.append("# API reference")
    out.append("")
    out.append("Every declaration of layerlab's public headers with the comment that documents it:")
    out.append("what each call does, the statuses it returns, who owns what, and which calls may run")
    out.append("on several threads at once. For the reader who calls the library from C or C++; the")
    out.append("material language is in `material-language.md`, the file formats in `formats.md`, and")
    out.append("what a renderer needs from the reader in `renderers.md`.")
    out.append("")
    out.append("Programs include `<layerlab.h>`. Declarations marked **experimental** are seen only")
    out.append("with `LL_EXPERIMENTAL` defined before the include and may change in a minor release;")
    out.append("all others are stable: a published stable declaration is never changed or removed")
    out.append("(`style.md`, items 2-3).")
    out.append("")
    out.append("This page is generated from `include/layerlab/*.h` by `scripts/api_doc.py`: edit the")
    out.append("header comments, then run `make api-doc`. `tests/api_doc.sh` fails when the page is")
    out.append("not current.")
    out.append("")
    out.append("## Functions")
    out.append("")
    out.append("| Function | Header | Tier |")
    out.append("|---|---|---|")
    for name, rel, top, entries in headers:
        for e in entries:
            names, kind = names_of(e.code)
            if kind != "function":
                continue
            for n in names:
                out.append("| [`%s`](#%s) | `%s` | %s |" % (
                    n, n.lower(), name, "experimental" if e.experimental else "stable"))
    out.append("")

    for name, rel, top, entries in headers:
        coded = [e for e in entries if e.code]
        whole = coded and all(e.experimental for e in coded)
        out.append("## %s%s" % (name, " (experimental)" if whole else ""))
        out.append("")
        if top:
            out.extend(fence(top))
            out.append("")
        for e in entries:
            names, kind = names_of(e.code)
            comment = e.comment or []
            if comment:
                rule = SECTION_RULE.match(comment[0].strip())
                if rule:
                    # A section rule: its title is a heading, the rest prose.
                    title = rule.group(1).strip()
                    if title:
                        out.append("### %s" % title)
                        out.append("")
                    comment = comment[1:]
            if e.code:
                if names:
                    anchors = "".join('<a id="%s"></a>' % n.lower() for n in names) if kind == "function" else ""
                    out.append("#### %s%s" % (anchors, ", ".join("`%s`" % n for n in names)))
                    out.append("")
                if e.experimental:
                    out.append("*Experimental* (declared with `LL_EXPERIMENTAL`).")
                    out.append("")
                out.extend(fence(e.code, "c"))
                out.append("")
            if comment:
                out.extend(fence(comment))
                out.append("")
    while out and not out[-1]:
        out.pop()
    return "\n".join(out) + "\n", problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("-o", "--output", help="write the page here (default: standard output)")
    parser.add_argument("--check", metavar="PAGE", help="fail unless PAGE is what would be written")
    args = parser.parse_args()
    page, problems = render()
    if problems:
        for p in problems:
            print(p, file=sys.stderr)
        print("api_doc: %d exported function(s) without a comment" % len(problems), file=sys.stderr)
        return 1
    if args.check:
        try:
            with open(args.check, encoding="utf-8") as f:
                current = f.read()
        except OSError as e:
            print("api_doc: %s: %s; run `make api-doc`" % (args.check, e.strerror), file=sys.stderr)
            return 1
        if current != page:
            diff = difflib.unified_diff(current.splitlines(), page.splitlines(),
                                        args.check, "from the headers", lineterm="", n=1)
            for k, line in enumerate(diff):
                if k == 40:
                    print("...", file=sys.stderr)
                    break
                print(line, file=sys.stderr)
            print("api_doc: %s is not current; run `make api-doc` and commit it" % args.check,
                  file=sys.stderr)
            return 1
        return 0
    if args.output:
        tmp = args.output + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(page)
        os.replace(tmp, args.output)
    else:
        sys.stdout.write(page)
    return 0


if __name__ == "__main__":
    sys.exit(main())
