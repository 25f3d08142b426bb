"""The house rules that a script can check (CONTRIBUTING.md, "House
rules"): no function over 150 lines and no struct with more than 12 public
mutable fields outside tests (scripts/long_functions.py,
scripts/wide_structs.py), and that each script finds what it is meant to
find in a planted file."""
import os
import subprocess
import sys
import tempfile
import textwrap
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import long_functions  # noqa: E402
import wide_structs  # noqa: E402


def planted(text):
    f = tempfile.NamedTemporaryFile("w", suffix=".h", delete=False)
    f.write(textwrap.dedent(text))
    f.close()
    return f.name


class Scripts(unittest.TestCase):
    def test_a_wide_struct_is_counted_and_what_is_not_data_is_not(self):
        fields = "\n".join(f"  double f{i} = {i};" for i in range(13))
        path = planted(f"""
            namespace x {{
            struct Wide {{
            {fields}
              static int s;
              const int c = 1;
              int method(int a) const {{ return a; }}
              struct Inner {{ int a, b; }};
              Inner inner{{1, 2}};
            }};
            struct Options {{
              double x = 0.10, y = 0.05;
              enum class Kind {{ kA, kB }} kind = Kind::kA;
              enum class Other {{ kC }};
              std::map<int, std::pair<int, int>> table;
              bool less = 1 < 2, more = 3 > 2;
            }};
            class Hidden {{
              int a, b, c, d, e, f, g, h, i, j, k, l, m;
             public:
              std::vector<std::pair<int, int>> pairs = {{}};
              void f();
            }};
            }}
            """)
        found = {name: count for _, name, count in wide_structs.structs(path)}
        self.assertEqual(found["Wide"], 14)  # 13 doubles and `inner`
        self.assertEqual(found["Inner"], 2)
        self.assertEqual(found["Hidden"], 1)  # private fields do not count
        self.assertEqual(found["Options"], 6)
        os.unlink(path)

    def test_a_long_function_is_found(self):
        body = "\n".join(f"  x += {i};" for i in range(160))
        path = planted(f"int longOne(int x) {{\n{body}\n  return x;\n}}\nint shortOne() {{ return 1; }}\n")
        found = long_functions.functions(path)
        lengths = {header.split("(")[0].split()[-1]: last - first + 1 for first, last, header in found}
        self.assertEqual(lengths["longOne"], 163)
        self.assertEqual(lengths["shortOne"], 1)
        os.unlink(path)


class Tree(unittest.TestCase):
    def check(self, script):
        run = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", script)],
                             capture_output=True, text=True)
        self.assertEqual(run.returncode, 0, run.stdout + run.stderr)

    def test_no_function_over_150_lines(self):
        self.check("long_functions.py")

    def test_no_struct_with_over_12_public_mutable_fields(self):
        self.check("wide_structs.py")


if __name__ == "__main__":
    unittest.main()
