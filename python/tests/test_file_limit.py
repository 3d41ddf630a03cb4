"""Writes over the file-size limit from Python (issue 41, item 1): a ValueError
saying "file too large" and naming the file, nothing left behind, and the
interpreter alive. The module does not touch SIGXFSZ (docs/limits.md,
"Python"): the interpreter ignores it at start-up, which this checks too."""
import os
import subprocess
import sys
import textwrap

# Run in a child interpreter: the limit must not reach pytest's own files.
CHILD = textwrap.dedent("""
    import resource, signal, sys
    import weft
    assert signal.getsignal(signal.SIGXFSZ) == signal.SIG_IGN, signal.getsignal(signal.SIGXFSZ)
    out, model = sys.argv[1], weft.YarnModel.load(sys.argv[2])
    resource.setrlimit(resource.RLIMIT_FSIZE, (2000, resource.getrlimit(resource.RLIMIT_FSIZE)[1]))
    for call in (lambda: weft.gather(preset="fleece", paths=2000, bins=[4, 8, 6, 12], seed=1,
                                     out=out + "/g"),
                 lambda: model.save(out + "/m.json")):
        try:
            call()
        except ValueError as e:
            print(e)
        else:
            print("no error")
""")


def test_writes_over_the_file_size_limit_raise_and_leave_nothing(tmp_path, root):
    model = root / "tests" / "data" / "fleece-small.json"
    r = subprocess.run([sys.executable, "-c", CHILD, str(tmp_path), str(model)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr  # not killed by SIGXFSZ (-25)
    lines = r.stdout.splitlines()
    assert len(lines) == 2, r.stdout
    assert f"cannot write '{tmp_path}/g/" in lines[0], lines[0]
    assert "file too large" in lines[0] and "file-size limit of 2000 bytes" in lines[0], lines[0]
    assert f"cannot write '{tmp_path}/m.json': file too large" in lines[1], lines[1]
    assert sorted(os.listdir(tmp_path)) == []
