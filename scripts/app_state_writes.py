"""Count the fields of the window's state that behaviour files write directly.

``LoudscapeApp`` (src/ui/state/mod.rs) is meant to hand each concern to one owner type that
changes its own state through its methods. This lists, for each field of ``LoudscapeApp``, the
files under src/ui/ (other than state/mod.rs) that write it, or part of it, without going
through a method of its owner: an assignment (``self.field = ...``, ``self.field.part += ...``),
a mutable borrow (``&mut self.field``) or a mutating standard-library call on it
(``self.field.take()``, ``.as_mut()``, ``.push(...)``, ...). Only files that add methods to
``LoudscapeApp`` (``impl LoudscapeApp``) and tests are read, so other types' own ``self`` fields
are not counted; in a test elsewhere only writes through ``app.``.

Run from the repository root: ``python3 scripts/app_state_writes.py`` (``-v`` lists the lines).
"""

import re
import sys
from collections import defaultdict
from pathlib import Path

STATE = Path("src/ui/state/mod.rs")
MUTATORS = (
    "as_mut|take|push|insert|clear|retain|get_or_insert_with|get_or_insert|remove|drain"
    "|extend|truncate|pop|replace|as_deref_mut|iter_mut|get_mut|entry|sort|dedup"
)


def write_patterns(receiver: str) -> list[re.Pattern[str]]:
    """Writes to a field of ``receiver`` (a regular expression for ``self.`` or ``app.``).

    The last pattern is a mutating call; its second group is the path between the field and
    the call (empty: called on the field itself).
    """
    return [
        re.compile(receiver + r"(\w+)(?:\.\w+|\[[^\]]*\])*\s*(?:[-+*/|&^]|<<|>>)?=(?!=)"),
        re.compile(r"&mut\s+" + receiver + r"(\w+)"),
        re.compile(receiver + r"(\w+)((?:\.\w+)*)\.(?:" + MUTATORS + r")\("),
    ]


APP_METHODS = write_patterns(r"\b(?:self|app)\.")
TESTS = write_patterns(r"\bapp\.")
STD = ("Option<", "Vec<", "HashMap<", "HashSet<", "String", "bool", "u32", "u64", "f32", "(")


def app_fields(text: str) -> dict[str, str]:
    """The fields of ``LoudscapeApp`` in state/mod.rs, by name, with their types."""
    body = text.split("struct LoudscapeApp {", 1)[1].split("\n}\n", 1)[0]
    return dict(re.findall(r"^\s*pub\([^)]*\)\s+(\w+):\s*([^\n]+?),?$", body, re.M))


def is_write(match: re.Match[str], types: dict[str, str]) -> bool:
    """Whether a match writes.

    A mutating call on an owner type's field counts only when it reaches inside it
    (``self.open.timeline.take()``), not a method of its own (``self.messages.clear(...)``);
    on a standard type (an ``Option``, a ``Vec``) it always counts.
    """
    if match.re.groups < 2 or match.group(2):
        return True
    return types[match.group(1)].startswith(STD)


def main() -> int:
    verbose = "-v" in sys.argv[1:]
    types = app_fields(STATE.read_text())
    writes: dict[str, set[str]] = defaultdict(set)
    lines: list[str] = []
    for path in sorted(Path("src/ui").rglob("*.rs")):
        if path == STATE:
            continue
        text = path.read_text()
        patterns = APP_METHODS if "impl LoudscapeApp" in text else TESTS
        for number, line in enumerate(text.splitlines(), 1):
            code = line.split("//", 1)[0]
            for pattern in patterns:
                for match in pattern.finditer(code):
                    field = match.group(1)
                    if field in types and is_write(match, types):
                        writes[field].add(str(path))
                        lines.append(f"{path}:{number}: {field}: {line.strip()}")
    for field in sorted(writes):
        print(f"{field}: {len(writes[field])} files: {', '.join(sorted(writes[field]))}")
    if verbose:
        print("\n".join(sorted(set(lines))))
    pairs = sum(len(files) for files in writes.values())
    print(
        f"{len(writes)} of {len(types)} fields of LoudscapeApp written directly "
        f"from other files ({pairs} field-file pairs)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
