"""The example of docs/python.md runs as written (its ```python blocks, in
order, in one namespace, from the repository root)."""
import re


def test_docs_example_runs(root, monkeypatch, capsys):
    text = (root / "docs" / "python.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 4
    monkeypatch.chdir(root)
    namespace = {"__name__": "docs_python_example"}
    for i, block in enumerate(blocks):
        exec(compile(block, f"docs/python.md block {i}", "exec"), namespace)
    out = capsys.readouterr().out
    assert "P(T|wi)" in out and "(32, 32, 3) float32 4" in out
