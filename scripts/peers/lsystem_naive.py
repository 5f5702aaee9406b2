"""The usual way to run an L-system, for scale against `lamina lsystem`: rewrite the whole
string in memory n times (str.translate, the fastest pure-Python rewriting), then walk it with
a turtle that merges runs of F (Hanafin et al.'s simplified turtle) into a list of segments.

Usage: python lsystem_naive.py N  (the paper's grammar X -> F[-X]F[+X]-X, F -> FF, 22 deg)
Prints the symbol, segment and simplified-segment counts, which must equal lamina's.
"""
import math
import sys

n = int(sys.argv[1])
rules = str.maketrans({"X": "F[-X]F[+X]-X", "F": "FF"})
word = "X"
for _ in range(n):
    word = word.translate(rules)

step, delta = 500.0, math.radians(22.0)
x, y, a = 0.0, 0.0, math.pi / 2
stack, segments, run, plain = [], [], 0, 0
for c in word:
    if c == "F":
        run += 1
        plain += 1
        continue
    if c == "X":
        continue
    if run:
        nx, ny = x + run * step * math.cos(a), y + run * step * math.sin(a)
        segments.append((x, y, nx, ny))
        x, y, run = nx, ny, 0
    if c == "+":
        a += delta
    elif c == "-":
        a -= delta
    elif c == "[":
        stack.append((x, y, a))
    elif c == "]":
        x, y, a = stack.pop()
if run:
    segments.append((x, y, x + run * step * math.cos(a), y + run * step * math.sin(a)))
print(len(word), plain, len(segments))
