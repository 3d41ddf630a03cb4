"""The chunk schema: every committed chunk file reads into a Chunk and writes back byte for
byte; a key missing, unknown or of the wrong type is named."""
import copy
import glob
import json
import os
import tempfile
import unittest

from table2lib import schema
from table2lib.config import ROOT

RESULTS = os.path.join(ROOT, "bench", "results")
CHUNK_FILES = sorted(glob.glob(os.path.join(RESULTS, "table2", "*-*.json")))


class RoundTrip(unittest.TestCase):
    def test_every_committed_chunk_file(self):
        self.assertEqual(len(CHUNK_FILES), 15)
        for path in CHUNK_FILES:
            with open(path) as f:
                text = f.read()
            chunk = schema.load_chunk(path)
            self.assertIsInstance(chunk, schema.Chunk)
            self.assertEqual(schema.to_dict(chunk), json.loads(text), path)
            self.assertEqual(schema.chunk_text(chunk), text, path)

    def test_write_chunk(self):
        chunk = schema.load_chunk(CHUNK_FILES[0])
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "a-b.json")
            schema.write_chunk(out, chunk)
            with open(out) as f, open(CHUNK_FILES[0]) as g:
                self.assertEqual(f.read(), g.read())

    def test_table2_json_cells_are_chunks(self):
        with open(os.path.join(RESULTS, "table2.json")) as f:
            table = json.load(f)
        for cell in table["cells"]:
            self.assertEqual(schema.to_dict(schema.from_dict(schema.Chunk, cell)), cell)

    def test_older_files_lack_keys_and_keep_lacking_them(self):
        # Chunks made before --ref-parts record neither settings.ref_parts nor the reference's
        # parts and seconds: read as None, written without them. (Every committed chunk has
        # been made again since: one of them with those keys taken out stands for the old ones.)
        with open(CHUNK_FILES[0]) as f:
            data = json.load(f)
        data["settings"].pop("ref_parts", None)
        for key in ("parts", "seconds"):
            data["fiber_reference"].pop(key, None)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "older.json")
            with open(path, "w") as f:
                json.dump(data, f)
            chunk = schema.load_chunk(path)
        self.assertIsNone(chunk.settings.ref_parts)
        self.assertIsNone(chunk.fiber_reference.parts)
        self.assertIsNone(chunk.fiber_reference.seconds)
        written = schema.to_dict(chunk)
        self.assertNotIn("ref_parts", written["settings"])
        self.assertNotIn("parts", written["fiber_reference"])
        self.assertNotIn("seconds", written["fiber_reference"])


class Errors(unittest.TestCase):
    def setUp(self):
        with open(CHUNK_FILES[0]) as f:
            self.data = json.load(f)

    def check(self, data, message):
        with self.assertRaises(schema.SchemaError) as e:
            schema.from_dict(schema.Chunk, data)
        self.assertIn(message, str(e.exception))

    def test_missing_key(self):
        data = copy.deepcopy(self.data)
        del data["fiber"]["equal_quality"]["levels"][1]["c"]
        self.check(data, "Chunk.fiber.equal_quality.levels[1]: missing key 'c'")

    def test_unknown_key(self):
        data = copy.deepcopy(self.data)
        data["neural"]["typo"] = 1
        self.check(data, "Chunk.neural: unknown key(s) typo")

    def test_wrong_type(self):
        data = copy.deepcopy(self.data)
        data["settings"]["size"] = "256"
        self.check(data, "Chunk.settings.size: expected an integer")
        data = copy.deepcopy(self.data)
        data["speedup"] = None
        self.check(data, "Chunk.speedup: expected a number")

    def test_numbers_keep_their_type(self):
        data = copy.deepcopy(self.data)
        data["speedup"] = 3  # an integral number stays an int, written as it was read
        self.assertEqual(schema.to_dict(schema.from_dict(schema.Chunk, data))["speedup"], 3)

    def test_other_format_is_not_a_chunk(self):
        data = dict(self.data, format=2)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "%s-%s.json" % (data["preset"], data["scene"]))
            with open(path, "w") as f:
                json.dump(data, f)
            with self.assertRaises(schema.SchemaError):
                schema.load_chunk(path)
            self.assertEqual(schema.chunk_files(tmp), [])


if __name__ == "__main__":
    unittest.main()
