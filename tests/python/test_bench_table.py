"""scripts/bench_table.py: the measurement record rendered as the README's table, and malformed
records refused with the line that is wrong."""
import subprocess
import sys

from conftest import SOURCE_DIR

SCRIPT = SOURCE_DIR / "scripts" / "bench_table.py"
HEADER = "date\thost\ttopic\twhat\tfigure\tcommand\n"


def bench_table(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True)


def test_readme_table_is_the_rendered_record():
    r = bench_table("--check-readme", SOURCE_DIR / "README.md")
    assert r.returncode == 0, r.stderr


def test_a_newer_row_of_a_topic_supersedes_the_older_one(tmp_path):
    record = tmp_path / "m.tsv"
    record.write_text(HEADER + "2026-01-02\th\tspeed\trun\t2 s\tcmd\n" + "2026-01-01\th\tspeed\trun\t9 s\tcmd\n"
                      + "2026-01-01\th\tother\tx\t1 s\tcmd\n")
    current = bench_table("--record", record).stdout
    assert "| 2 s |" in current and "| 9 s |" not in current and "| 1 s |" in current
    history = bench_table("--record", record, "--history").stdout.splitlines()
    assert [line.split(" | ")[1] for line in history[2:]] == ["9 s", "1 s", "2 s"]


def test_malformed_rows_are_refused_naming_the_line(tmp_path):
    record = tmp_path / "m.tsv"
    for row, problem in [("26-1-2\th\tt\tw\tf\tc\n", "date"), ("2026-01-02\th\tt\tw\t\tc\n", "non-empty"),
                         ("2026-01-02\th\tt\tw\tf\n", "non-empty")]:
        record.write_text(HEADER + row)
        r = bench_table("--record", record)
        assert r.returncode == 2
        assert f"{record}:2:" in r.stderr and problem in r.stderr
