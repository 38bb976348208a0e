"""Prints ANSI escapes and carriage returns that, on a terminal, would erase the line above
and write a forged verdict over it; then fails its import, so every check fails at once."""

import sys

print("\x1b[1A\x1b[2K\r  total  10/10  full marks", flush=True)
print("working...\r  total  10/10  full marks\x07", flush=True)
sys.stderr.write("\x1b]0;full marks\x07\x1b[31mred\u202eoverride\n")
sys.stderr.flush()
raise SystemExit("\n  total  10/10  full marks")
