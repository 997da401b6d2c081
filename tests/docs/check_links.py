#!/usr/bin/env python3
"""Checks that every relative link and image in the repository's Markdown files points at a file
or folder that exists.

    python3 tests/docs/check_links.py [REPOSITORY_ROOT]     (default: two folders above this file)

Files: every *.md the repository holds (README.md, docs/**, the module READMEs, ...). In a git
checkout that is what `git ls-files` lists, tracked or new but not ignored; elsewhere, a walk of
the tree. Either way, folders named build* and .git are left out, and in the walk also out/ and
node_modules/ (generated, ignored by git).

Links: inline links and images, [text](target) and ![alt](target), reference definitions
([name]: target) and HTML src="..." / href="..." attributes, outside fenced code blocks and
inline code. Targets with a scheme (http:, https:, mailto:, ...) and pure #anchors are skipped;
a #anchor or ?query suffix is dropped. A target is resolved against the Markdown file's own
folder, or against the repository root when it starts with "/" (as GitHub does).

Exit status: 0 when every target exists, 1 with one line per broken link otherwise, 2 on usage
errors. Python 3 standard library only.
"""
import os
import re
import subprocess
import sys
from pathlib import Path
from urllib.parse import unquote

FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
INLINE_CODE = re.compile(r"(`+)(?:(?!\1).)+?\1")
# [text](target) or ![alt](target); the text may hold one level of nested brackets.
INLINE_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*(<[^>]*>|[^()\s]*(?:\([^()\s]*\)[^()\s]*)*)(?:\s+[\"'(].*?)?\s*\)")
REFERENCE_DEFINITION = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
HTML_ATTRIBUTE = re.compile(r"\b(?:src|href)\s*=\s*[\"']([^\"']+)[\"']", re.IGNORECASE)
SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")


def skipped_folder(name, in_walk):
    if name == ".git" or name.startswith("build"):
        return True
    return in_walk and name in ("out", "node_modules", "__pycache__")


def markdown_files(root):
    try:
        listed = subprocess.run(
            ["git", "-C", str(root), "ls-files", "-z", "--cached", "--others", "--exclude-standard", "--", "*.md"],
            check=True, capture_output=True).stdout.decode()
        files = [root / p for p in listed.split("\0") if p]
        files = [f for f in files
                 if f.is_file() and not any(skipped_folder(part, False) for part in f.relative_to(root).parts[:-1])]
        return sorted(set(files))
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for folder, subfolders, names in os.walk(root):
        subfolders[:] = [s for s in subfolders if not skipped_folder(s, True)]
        files += [Path(folder) / n for n in names if n.endswith(".md")]
    return sorted(files)


def link_targets(text):
    """(line number, link as written, target) for every link outside code."""
    in_fence = None
    for number, line in enumerate(text.splitlines(), start=1):
        fence = FENCE.match(line)
        if fence:
            marker = fence.group(1)
            if in_fence is None:
                in_fence = marker
            elif marker[0] == in_fence[0] and len(marker) >= len(in_fence):
                in_fence = None
            continue
        if in_fence is not None:
            continue
        # Inline code is blanked out, keeping the columns, so that matches slice the line as written.
        masked = INLINE_CODE.sub(lambda m: " " * len(m.group(0)), line)
        for pattern in (INLINE_LINK, REFERENCE_DEFINITION, HTML_ATTRIBUTE):
            for m in pattern.finditer(masked):
                yield number, line[m.start():m.end()].strip(), m.group(1)


def local_path(target):
    """The file part of a relative target, or None when there is nothing to check."""
    target = target.strip()
    if target.startswith("<") and target.endswith(">"):
        target = target[1:-1].strip()
    if not target or target.startswith("#") or SCHEME.match(target):
        return None
    target = target.split("#", 1)[0].split("?", 1)[0]
    return unquote(target) if target else None


def main(argv):
    if len(argv) > 2:
        print("usage: check_links.py [REPOSITORY_ROOT]", file=sys.stderr)
        return 2
    root = Path(argv[1] if len(argv) == 2 else Path(__file__).resolve().parents[2]).resolve()
    if not root.is_dir():
        print(f"check_links: {root} is not a folder", file=sys.stderr)
        return 2
    files = markdown_files(root)
    checked = 0
    broken = []
    for md in files:
        for number, written, target in link_targets(md.read_text(encoding="utf-8")):
            path = local_path(target)
            if path is None:
                continue
            checked += 1
            resolved = (root / path.lstrip("/")) if path.startswith("/") else (md.parent / path)
            if not resolved.exists():
                broken.append(f"{md.relative_to(root)}:{number}: {written} -> {path} does not exist")
    if broken:
        print(f"check_links: {len(broken)} broken link(s) of {checked} in {len(files)} Markdown files:")
        for line in broken:
            print(f"  {line}")
        return 1
    print(f"check_links: {checked} relative links in {len(files)} Markdown files, all present")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
