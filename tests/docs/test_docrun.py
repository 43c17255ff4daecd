"""The rules the documentation tests apply (tests/docs/docrun.py), on small known cases."""
from __future__ import annotations

import pytest
from docrun import compare, number_matches, parse, split_commands

PRINTED = """\
strategy      T_rip/N*m  psi_rip/Wb  faults  wall/s      THD window/s
conventional     0.0816      0.0018       0    0.08      [0.4, 0.595)
s1               0.0892      0.0019       0    0.06      [0.4, 0.595)
conventional states   1000000  mismatches 0  (618,740 states/s, guard trips 64778)
"""


@pytest.mark.parametrize("quoted,printed,ok", [
    ("64778", "64778", True), ("64428", "64778", False),        # counts: equal
    ("500,728", "500728", True),                                 # thousands separators are not decimals
    ("0.0816", "0.0830", True), ("0.0816", "0.0900", False),     # 5 %
    ("0.0018", "0.0019", True), ("0.0018", "0.0021", False),     # one unit of the last digit (> 5 %)
    ("0.001", "0.0014", True), ("1.5e+04", "15000", True), ("11.68", "12.5", False),
])
def test_tolerance_rule(quoted, printed, ok):
    assert number_matches(quoted, printed) is ok


def test_quoted_lines_match_in_order_with_timing_and_elision():
    good = """\
strategy      T_rip/N*m  psi_rip/Wb  faults  wall/s      THD window/s
conventional     0.0816      0.0018       0   ~0.04      [0.4, 0.595)
...
conventional states   1000000  mismatches 0  (~500,000 states/s, ...)
"""
    assert compare(good, PRINTED, "") == []
    # a number that differs, a timing figure that is missing, lines out of order
    assert "numbers differ: 0.0900" in compare(good.replace("0.0816", "0.0900"), PRINTED, "")[0]
    assert compare("conventional states   1000000  mismatches 0  (~500,000 ...)", "conventional states   "
                   "1000000  mismatches 0  (fast, guard trips 1)", "") != []
    assert compare("s1  0.0892  0.0019  0  ~0.06  [0.4, 0.595)\nconventional  0.0816  0.0018  0  ~0.08  "
                   "[0.4, 0.595)", PRINTED, "") != []
    # text must match exactly, whatever the spacing; stderr is searched too
    assert compare("s2  0.0892  0.0019  0  ~0.06  [0.4, 0.595)", PRINTED, "") != []
    assert compare("mpcgen: warning: x = 5.0: above 20 A", "", "mpcgen: warning: x = 5.0: above 20 A\n") == []


def test_blocks_pair_commands_with_the_output_right_after():
    md = """\
```sh
mpcgen a   # refused: exit code 2
```

```text
out
```

prose

```sh
python3 - x <<'EOF'
print(1)
EOF
mpcgen b \\
    --c
```

between

```text
not this block's
```
"""
    steps = parse(md).steps
    assert [s.output is not None for s in steps] == [True, False]
    cmds = steps[0].command_lines()
    assert [(c.text, c.exit_code, c.line) for c in cmds] == [("mpcgen a   # refused: exit code 2", 2, 2)]
    second = split_commands(steps[1].commands.text)
    assert [c.text for c in second] == ["python3 - x <<'EOF'\nprint(1)\nEOF", "mpcgen b  --c"]
