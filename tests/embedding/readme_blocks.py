"""Prints the code block of one language under one section of README.md, exactly as printed.

    readme_blocks.py README.md SECTION LANGUAGE [INDEX]

SECTION is the text of a "## " heading ("Embedding", "Python"); the section runs to the next
"## " heading. LANGUAGE is the fence's info string (cmake, cpp, python); INDEX picks among the
blocks of that language in the section (default 0). Exits 1, naming what is missing, when the
section or the block is not there, so a README edit that drops a block fails its test.
"""
import sys


def block(text, section, language, index=0):
    lines = text.splitlines()
    try:
        start = lines.index("## " + section)
    except ValueError:
        raise SystemExit(f"README: no section '## {section}'")
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")), len(lines))
    found, inside, body = [], False, []
    for line in lines[start + 1:end]:
        if not inside and line.strip() == "```" + language:
            inside, body = True, []
        elif inside and line.strip() == "```":
            inside = False
            found.append("\n".join(body) + "\n")
        elif inside:
            body.append(line)
    if index >= len(found):
        raise SystemExit(f"README: section '{section}' has {len(found)} ```{language} block(s), not {index + 1}")
    return found[index]


if __name__ == "__main__":
    readme, section, language = sys.argv[1:4]
    index = int(sys.argv[4]) if len(sys.argv) > 4 else 0
    with open(readme, encoding="utf-8") as f:
        sys.stdout.write(block(f.read(), section, language, index))
