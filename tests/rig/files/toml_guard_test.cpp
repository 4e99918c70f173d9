// The TOML guard (rig/files/toml_guard.hpp) against the TOML 1.0 specification: every construct the
// spec shows (written here from toml.io/en/v1.0.0) passes it and parses with toml++, as do the
// project's own files; the inputs on which toml++ 3.3.0 has undefined behaviour are refused with a
// line and column. The fuzz targets scene_file and pedal_config run toml++ behind it with its
// assertions and UBSan on (tests/fuzz).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "rig/files/toml_guard.hpp"

using vitreo::files::toml_guard;

namespace {
const std::vector<std::string> kValid = {
    "# a comment\nkey = \"value\"  # and another\n",
    "bare_key = 1\nbare-key = 2\n1234 = 3\n\"127.0.0.1\" = 4\n\"ʎǝʞ\" = 5\n'quoted \"value\"' = 6\n\"\" = 7\n",
    "name = \"Orange\"\nphysical.color = \"orange\"\nsite.\"google.com\" = true\nfruit . flavor = \"banana\"\n",
    "3.14159 = \"pi\"\n",
    "str = \"I'm a string. \\\"You can quote me\\\". Name\\tJos\\u00E9\\nLocation\\tSF.\"\n",
    "str1 = \"\"\"\nRoses are red\nViolets are blue\"\"\"\n",
    "str3 = \"\"\"\\\n       The quick brown \\\n       fox jumps over \\\n       the lazy dog.\\\n       \"\"\"\n",
    "str4 = \"\"\"Here are two quotation marks: \"\". Simple enough.\"\"\"\nstr6 = \"\"\"Here are fifteen quotation marks: \"\"\\\"\"\"\\\"\"\"\\\"\"\"\\\"\"\"\\\".\"\"\"\n"
    "str7 = \"\"\"\"This,\" she said, \"is just a pointless statement.\"\"\"\"\n",
    "winpath = 'C:\\Users\\nodejs\\templates'\nregex = '<\\i\\c*\\s*>'\n",
    "regex2 = '''I [dw]on't need \\d{2} apples'''\nlines = '''\nThe first newline is\ntrimmed in raw strings.\n'''\n",
    "quot15 = '''Here are fifteen quotation marks: \"\"\"\"\"\"\"\"\"\"\"\"\"\"\"'''\napos15 = \"Here are fifteen apostrophes: '''''''''''''''\"\n"
    "str = ''''That,' she said, 'is still pointless.''''\n",
    "int1 = +99\nint2 = 42\nint3 = 0\nint4 = -17\nint5 = 1_000\nint6 = 5_349_221\nhex1 = 0xDEADBEEF\nhex3 = 0xdead_beef\n"
    "oct1 = 0o01234567\nbin1 = 0b11010110\n",
    "flt1 = +1.0\nflt2 = 3.1415\nflt3 = -0.01\nflt4 = 5e+22\nflt5 = 1e06\nflt6 = -2E-2\nflt7 = 6.626e-34\n"
    "flt8 = 224_617.445_991_228\nsf1 = inf\nsf2 = +inf\nsf3 = -inf\nsf4 = nan\nsf5 = +nan\nsf6 = -nan\n",
    "bool1 = true\nbool2 = false\n",
    "odt1 = 1979-05-27T07:32:00Z\nodt2 = 1979-05-27T00:32:00-07:00\nodt3 = 1979-05-27T00:32:00.999999-07:00\n"
    "odt4 = 1979-05-27 07:32:00Z\nldt1 = 1979-05-27T07:32:00\nld1 = 1979-05-27\nlt1 = 07:32:00\nlt2 = 00:32:00.999999\n",
    "integers = [ 1, 2, 3 ]\ncolors = [ \"red\", \"yellow\", \"green\" ]\nnested_arrays_of_ints = [ [ 1, 2 ], [3, 4, 5] ]\n"
    "nested_mixed_array = [ [ 1, 2 ], [\"a\", \"b\", \"c\"] ]\nstring_array = [ \"all\", 'strings', \"\"\"are the same\"\"\", '''type''' ]\n"
    "numbers = [ 0.1, 0.2, 0.5, 1, 2, 5 ]\ncontributors = [\n  \"Foo Bar <foo@example.com>\",\n"
    "  { name = \"Baz Qux\", email = \"bazqux@example.com\", url = \"https://example.com/bazqux\" }\n]\n",
    "integers2 = [\n  1, 2, 3\n]\nintegers3 = [\n  1,\n  2, # this is ok\n]\nempty = []\nempty2 = [ ]\n",
    "[table-1]\nkey1 = \"some string\"\nkey2 = 123\n\n[table-2]\nkey1 = \"another string\"\nkey2 = 456\n",
    "[dog.\"tater.man\"]\ntype.name = \"pug\"\n[ j . \"ʞ\" . 'l' ]\n[ g .  h  . i ]\n",
    "name = { first = \"Tom\", last = \"Preston-Werner\" }\npoint = { x = 1, y = 2 }\nanimal = { type.name = \"pug\" }\nempty = {}\n",
    "[[products]]\nname = \"Hammer\"\nsku = 738594937\n\n[[products]]  # empty table within the array\n\n[[products]]\nname = \"Nail\"\n",
    "[[fruits]]\nname = \"apple\"\n[fruits.physical]\ncolor = \"red\"\n[[fruits.varieties]]\nname = \"red delicious\"\n"
    "[[ fruits.varieties ]]\nname = \"granny smith\"\n",
    "points = [ { x = 1, y = 2, z = 3 },\n           { x = 7, y = 8, z = 9 },\n           { x = 2, y = 4, z = 8 } ]\n",
    "\xEF\xBB\xBF" "a = 1\r\nb = \"two\"\r\n# µ in a comment, ß and 日本 in strings:\r\nc = \"µß日本\"\r\n",
    "a=1\nb=[1,2]\nc={d=\"e\"}\nf.g='h'\n",
    "key = \"value\"\t# tab before the comment\n\tindented = true\n",
};

// Each toml++ 3.3.0 misbehaves on (an assertion in a debug build, __builtin_unreachable or a broken
// optimiser assumption in the release library) — found by hand (issue 20) and by the fuzz targets.
const std::vector<std::pair<std::string, std::string>> kRefused = {
    {"[&x]\n", "table header must start with a key"},
    {"[[[a]]]\n", "table header must start with a key"},
    {"[=\n", "table header must start with a key"},
    {"fo \xC2\xB5 = 1\n", "non-ASCII character outside"},
    {"a = 1\xC2\xB5" "\n", "non-ASCII character outside"},
    {"a = \"x\" \xC2\xB5\n", "non-ASCII character outside"},
    {"a = \"\"\"\\\n  \xC2\xB5\"\"\"\n", "right after a line-ending backslash"},
    {"\"\"\"\\\xEF\xBB\x90" "'\n", "after a backslash"},
    {"z_=0'&&\xC7\xA7=-'\n", "quote in the middle of a bare value"},
    {"f=[}\n", "a value or ']' was expected"},
    {"z=22\n[;\n", "table header must start with a key"},
    {std::string("5555=5=\b\0\"[\xEF\xBB\xBE", 12), "control character (0x08)"},
    {"a = {,}\n", "a key or '}' was expected"},
    {"a = ,\n", "a value was expected"},
};
}  // namespace

TEST(TomlGuard, EveryConstructOfTheSpecPassesAndParses) {
  for (const std::string& text : kValid) {
    const auto p = toml_guard(text);
    EXPECT_FALSE(p) << "refused valid TOML at line " << p.line << ", column " << p.column << ": " << p.why << "\n" << text;
    if (p) continue;
    EXPECT_NO_THROW((void)toml::parse(text)) << text;
  }
}

TEST(TomlGuard, TheProjectsOwnTomlFilesPass) {
  int files = 0;
  for (const char* dir : {"/scenes", "/rig/config"}) {
    for (const auto& e : std::filesystem::directory_iterator(std::string(VITREO_SOURCE_DIR) + dir)) {
      if (e.path().extension() != ".toml") continue;
      std::ifstream f(e.path());
      const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
      const auto p = toml_guard(text);
      EXPECT_FALSE(p) << e.path() << ":" << p.line << ":" << p.column << ": " << p.why;
      ++files;
    }
  }
  EXPECT_GE(files, 12);
}

TEST(TomlGuard, WhatTomlPlusPlus330MisbehavesOnIsRefusedWithLineAndColumn) {
  for (const auto& [text, says] : kRefused) {
    const auto p = toml_guard(text);
    ASSERT_TRUE(p) << "passed: " << text;
    EXPECT_NE(p.why.find(says), std::string::npos) << p.why << " (for: " << text << ")";
    EXPECT_GE(p.line, 1);
    EXPECT_GE(p.column, 1);
  }
  const auto p = toml_guard("a = 1\nb = 2\n  fo \xC2\xB5 = 1\n");
  EXPECT_EQ(p.line, 3);
  EXPECT_EQ(p.column, 6);
}
