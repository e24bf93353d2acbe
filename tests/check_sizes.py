#!/usr/bin/python3
"""The size rule: no tracked source file over 600 lines and no function over 80 lines (from its
signature's first line to its closing brace, or to the last line of a Python def).

    check_sizes.py [ROOT]

Lists the tracked sources with `git ls-files` (C++, CUDA, Python and JavaScript files under the
source folders; not node_modules or third-party code) and prints FILE:LINE, the function's first
line and its length for every function over the limit, and FILE for every file over it; exits 1
when there is any, 77 (a skip) when git or the checkout is missing.

Functions are found by braces in the text with comments, strings and preprocessor lines blanked:
C++ functions and member functions at namespace or class scope (a signature that ends in `)`,
with qualifiers or a constructor's initialisers after it; TEST bodies), lambdas and local classes
counting toward the function that holds them; Python defs through the ast module (nested ones
toward theirs as well as on their own); JavaScript function declarations, class methods and arrow
functions with a block body assigned to const, let or var.
"""
import ast
import re
import subprocess
import sys
from pathlib import Path

MAX_FILE_LINES = 600
MAX_FUNCTION_LINES = 80
FOLDERS = ("src", "include", "apps", "python", "tests", "bench", "paraview", "fuzz", "web", "tools")
CPP = (".cpp", ".h", ".hpp", ".cc", ".cu", ".cuh")
SKIP_PARTS = {"node_modules", "third_party", "thirdparty", "third-party", "external", "vendor"}
SKIP_CODE = 77


def tracked_sources(root):
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--", *FOLDERS], cwd=root, capture_output=True, check=True)
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"skipped: git cannot list the files of {root} ({e})")
        sys.exit(SKIP_CODE)
    files = []
    for name in out.stdout.decode().split("\0"):
        if not name or not name.endswith(CPP + (".py", ".js", ".mjs")) or name.endswith(".min.js"):
            continue
        if SKIP_PARTS & set(Path(name).parts):
            continue
        if (root / name).is_file():
            files.append(name)
    return files


def literal_end(text, i, quote):
    """The offset of the character that closes the literal opened by `quote` at i (a string, a
    character, a JS template or regex literal), or where the line ends for an unclosed one."""
    n = len(text)
    j = i + 1
    in_class = False
    while j < n:
        d = text[j]
        if d == "\\":
            j += 2
            continue
        if quote == "/":
            if d == "\n":
                break
            if d == "[":
                in_class = True
            elif d == "]":
                in_class = False
            elif d == "/" and not in_class:
                break
        elif d == quote:
            break
        elif quote == "`" and text.startswith("${", j):
            # A template literal's expression: skipped with its own braces.
            depth, j = 1, j + 2
            while j < n and depth:
                depth += {"{": 1, "}": -1}.get(text[j], 0)
                j += 1
            continue
        elif quote != "`" and d == "\n":
            break
        j += 1
    return j


def blank(text, js=False):
    """The text with comments, string and character literals (and in C++ preprocessor lines)
    replaced by spaces; newlines kept, so offsets and line numbers stay."""
    out = list(text)
    n, i = len(text), 0
    at_line_start = True
    prev = ""  # the last significant character, to tell a JS regex from a division

    def wipe(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = text[i]
        if c == "\n":
            at_line_start = True
            i += 1
            continue
        if c in " \t\r":
            i += 1
            continue
        if not js and at_line_start and c == "#":
            j = i
            while j < n and text[j] != "\n":
                j = j + 2 if text[j] == "\\" else j + 1
            wipe(i, min(j, n))
            i = j
            continue
        at_line_start = False
        two = text[i:i + 2]
        if two == "//":
            j = text.find("\n", i)
            j = n if j < 0 else j
            wipe(i, j)
            i = j
            continue
        if two == "/*":
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            wipe(i, j)
            i = j
            continue
        if not js and c == "R" and text[i + 1:i + 2] == '"':  # raw string R"d(...)d"
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if m:
                end = text.find(")" + m.group(1) + '"', i)
                j = n if end < 0 else end + len(m.group(1)) + 2
                wipe(i + 1, j)
                i, prev = j, '"'
                continue
        if c in "\"'" or (js and c == "`") or (js and c == "/" and prev in "(,=:[!&|?{};+-*%<>~^" ):
            quote = c
            j = literal_end(text, i, quote)
            wipe(i + 1, min(j, n))
            i, prev = j + 1, quote
            continue
        prev = c
        i += 1
    return "".join(out)


def matching(text, open_at):
    """The offset of the brace that closes the one at `open_at` (the end of the text if none)."""
    depth = 0
    for k in range(open_at, len(text)):
        if text[k] == "{":
            depth += 1
        elif text[k] == "}":
            depth -= 1
            if depth == 0:
                return k
    return len(text) - 1


SCOPE = re.compile(r"^(?:export\s+)?(?:inline\s+)?(namespace|class|struct|union|enum|extern)\b")
ACCESS = re.compile(r"^\s*(?:(?:public|private|protected|signals|slots|Q_SLOTS)\s*:(?!:)\s*)+")
TEMPLATE = re.compile(r"^\s*template\s*<")
# After a parameter list: qualifiers, a trailing return type, a requires clause.
FUNCTION_TAIL = re.compile(
    r"\)\s*(?:(?:const|volatile|noexcept(?:\s*\([^()]*\))?|override|final|mutable|constexpr|&&|&|"
    r"throw\s*\([^()]*\)|__attribute__\s*\(\(.*?\)\))\s*)*(?:->\s*[^{;=]+)?(?:requires\s+[^{;]+)?$", re.S)
INIT_LIST = re.compile(r"\)\s*(?:noexcept\s*)?:\s*[^;]*$", re.S)


def strip_template(head):
    """The head without its leading template parameter lists."""
    while True:
        m = TEMPLATE.match(head)
        if not m:
            return head
        depth, k = 0, m.end() - 1
        while k < len(head):
            depth += {"<": 1, ">": -1}.get(head[k], 0)
            if depth == 0:
                break
            k += 1
        head = head[k + 1:]


def cpp_functions(text):
    """(first line, last line) of each C++ function at namespace or class scope (1-based)."""
    code = blank(text)
    line_of = _line_index(code)
    found = []

    def scan(begin, end):
        head_start = begin
        k = begin
        while k < end:
            c = code[k]
            if c in ";}":
                head_start = k + 1
            elif c == "{":
                raw = code[head_start:k]
                access = ACCESS.match(raw)
                head = raw[access.end():] if access else raw
                first = line_of(head_start + len(raw) - len(head) + len(head) - len(head.lstrip()))
                body = strip_template(head).strip()
                close = matching(code, k)
                if SCOPE.match(body) and not _assigns(body):
                    scan(k + 1, close)  # a namespace, class or enum: functions inside
                    head_start = k = close + 1
                    continue
                if INIT_LIST.search(body) and re.search(r"[\w>]\s*$", body):
                    k = close + 1  # a member's braced initialiser in a constructor's list
                    continue
                lambda_ = re.search(r"=\s*\[[^\]]*\]\s*(?:\([^()]*\))?[^=]*$", body, re.S)
                if lambda_ or (body and not _assigns(body) and (FUNCTION_TAIL.search(body) or INIT_LIST.search(body))):
                    found.append((first, line_of(close), body))
                head_start = k = close + 1
                continue
            k += 1

    scan(0, len(code))
    return found


def _assigns(head):
    """Whether a head holds `=` outside parentheses (an initialiser, not a signature)."""
    head = re.sub(r"\boperator\s*[^\w\s(]+\s*(?=\()", "operator", head)
    depth = 0
    for k, c in enumerate(head):
        if c in "([":
            depth += 1
        elif c in ")]":
            depth -= 1
        elif c == "=" and depth == 0 and head[k + 1:k + 2] != "=" and head[k - 1:k] not in ("=", "!", "<", ">"):
            return True
    return False


def _line_index(text):
    starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def line_of(offset):
        lo, hi = 0, len(starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if starts[mid] <= offset:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1

    return line_of


JS_FUNCTION = re.compile(
    r"^[ \t]*(?:export\s+(?:default\s+)?)?(?:async\s+)?function\b\s*\*?\s*[\w$]*\s*\(|"
    r"^[ \t]*(?:export\s+)?(?:const|let|var)\s+[\w$]+\s*=\s*(?:async\s+)?(?:function\b\s*\*?\s*[\w$]*\s*\(|"
    r"\(|[\w$]+\s*=>)|"
    r"^[ \t]*(?:static\s+)?(?:async\s+)?(?:get\s+|set\s+)?\*?\s*(?!(?:if|for|while|switch|catch|function|return|"
    r"with|do|else|new|typeof|await|yield)\b)[\w$#]+\s*\(", re.M)


def js_functions(text):
    """(first line, last line) of each JavaScript function declaration, method and block-bodied
    arrow function assigned to a variable; nested ones count toward the outer one."""
    code = blank(text, js=True)
    line_of = _line_index(code)
    found = []
    k = 0
    while True:
        m = JS_FUNCTION.search(code, k)
        if not m:
            break
        # The parameter list (if the match opened one), then `=>` or nothing, then the body's brace.
        j = m.end()
        if code[j - 1] == "(":
            depth = 1
            while j < len(code) and depth:
                depth += {"(": 1, ")": -1}.get(code[j], 0)
                j += 1
        rest = code[j:]
        body = re.match(r"\s*(?:=>\s*)?\{", rest)
        is_method = not re.match(r"\s*(?:export\s+)?(?:const|let|var|async|function)\b", m.group(0)) and \
            "=>" not in m.group(0) and not m.group(0).lstrip().startswith("function")
        if not body or (is_method and code[m.start():j].strip().endswith(")") and re.match(r"\s*=>", rest)):
            k = m.end()
            continue
        open_at = j + body.end() - 1
        if is_method and not _in_class_or_object(code, m.start()):
            k = m.end()
            continue
        close = matching(code, open_at)
        found.append((line_of(m.start() + len(m.group(0)) - len(m.group(0).lstrip())), line_of(close),
                      code[m.start():j].strip()))
        k = close + 1
    return found


def _in_class_or_object(code, at):
    """Whether the text at `at` lies directly in a class body or an object literal (a method)."""
    depth, k = 0, at - 1
    while k >= 0:
        c = code[k]
        if c == "}":
            depth += 1
        elif c == "{":
            if depth == 0:
                before = code[:k].rstrip()
                return bool(re.search(r"\bclass\b[^{;()]*$", before) or before.endswith(("=", "(", ",", ":", "return")))
            depth -= 1
        k -= 1
    return False


def py_functions(text):
    try:
        tree = ast.parse(text)
    except SyntaxError:
        return None
    return [(n.lineno, n.end_lineno, "def " + n.name) for n in ast.walk(tree)
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]


def check(root, names):
    problems = []
    for name in names:
        text = (root / name).read_text(errors="replace")
        lines = text.split("\n")
        count = len(lines) - (1 if text.endswith("\n") else 0)
        if count > MAX_FILE_LINES:
            problems.append(f"{name}: {count} lines (at most {MAX_FILE_LINES})")
        if name.endswith(".py"):
            functions = py_functions(text)
            if functions is None:
                problems.append(f"{name}: not valid Python")
                continue
        elif name.endswith((".js", ".mjs")):
            functions = js_functions(text)
        else:
            functions = cpp_functions(text)
        for first, last, _ in functions:
            length = last - first + 1
            if length > MAX_FUNCTION_LINES:
                problems.append(f"{name}:{first}: {lines[first - 1].strip()} ({length} lines, at most "
                                f"{MAX_FUNCTION_LINES})")
    return problems


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent).resolve()
    names = tracked_sources(root)
    problems = check(root, names)
    for p in problems:
        print(p)
    print(f"{len(names)} files checked, {len(problems)} over the limits")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
