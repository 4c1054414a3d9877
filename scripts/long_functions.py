#!/usr/bin/env python3
"""Lists C++ function bodies longer than a limit (default 100 lines).

Usage: python3 scripts/long_functions.py [--limit N] [--check] [paths...]   (default: core/)
With --check the exit status is 1 when any function is longer than the limit.

A text scan, not a parser: comments, strings and character literals are blanked,
then every brace block whose opening follows a closing parenthesis (optionally
followed by qualifiers such as const, noexcept, override, -> type or an
initialiser list) and that is not nested inside another function is counted,
from the line of its name to its closing brace. Lambdas and control blocks count
towards the function that holds them, as a reader sees them.
"""
import argparse
import pathlib
import re
import sys

CONTROL = re.compile(r"\b(if|for|while|switch|catch|do|else)\s*$")


def blank_comments_and_strings(text):
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif text.startswith('R"', i):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + c); i = j + 1
        else:
            out.append(c); i += 1
    return "".join(out)


def header_name(head):
    """The function name before the parameter list, or None if `head` is no function."""
    head = re.sub(r"\s+", " ", head).strip()
    if not head.endswith(")") and not re.search(r"\)[^()]*$", head):
        return None
    # Strip an initialiser list (": a_(x), b_(y)") and trailing qualifiers.
    depth, cut = 0, None
    for k, ch in enumerate(head):
        if ch == "(":
            if depth == 0 and cut is None:
                cut = k
            depth += 1
        elif ch == ")":
            depth -= 1
    if cut is None:
        return None
    before = head[:cut].rstrip()
    if CONTROL.search(before) or before.endswith("]"):
        return None  # control statement or lambda
    m = re.search(r"([~\w:<>]+(?:operator\s*\S+)?)$", before)
    return m.group(1) if m else None


def long_functions(path, limit):
    text = blank_comments_and_strings(path.read_text(errors="replace"))
    # Preprocessor lines (#if defined(X) ...) would read as a function head.
    text = re.sub(r"(?m)^[ \t]*#.*$", lambda m: " " * len(m.group(0)), text)
    found, stack, last_stmt_end = [], [], 0
    for pos, ch in enumerate(text):
        if ch in ";}":
            if ch == ";":
                last_stmt_end = pos + 1
        if ch == "{":
            inside_function = any(kind == "fn" for kind, *_ in stack)
            head = text[last_stmt_end:pos]
            name = None if inside_function else header_name(head.split("{")[-1].split("}")[-1])
            if name:
                start = text.count("\n", 0, last_stmt_end + len(head) - len(head.lstrip()))
                stack.append(("fn", name, start + 1))
            else:
                stack.append(("block", None, None))
            last_stmt_end = pos + 1
        elif ch == "}":
            if stack:
                kind, name, start = stack.pop()
                if kind == "fn":
                    end = text.count("\n", 0, pos) + 1
                    if end - start + 1 > limit:
                        found.append((end - start + 1, f"{path}:{start}-{end}", name))
            last_stmt_end = pos + 1
    return found


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--limit", type=int, default=100)
    ap.add_argument("--check", action="store_true", help="exit 1 if any function is too long")
    ap.add_argument("paths", nargs="*", default=["core"])
    args = ap.parse_args()
    rows = []
    for root in args.paths:
        p = pathlib.Path(root)
        files = [p] if p.is_file() else sorted(
            f for f in p.rglob("*") if f.suffix in {".cpp", ".cc", ".h", ".hpp"})
        for f in files:
            rows += long_functions(f, args.limit)
    for lines, where, name in sorted(rows, reverse=True):
        print(f"{lines:5d}  {where}  {name}")
    print(f"{len(rows)} function(s) longer than {args.limit} lines", file=sys.stderr)
    return 1 if args.check and rows else 0


if __name__ == "__main__":
    sys.exit(main())
