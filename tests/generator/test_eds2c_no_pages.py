"""eds2c --no-pages: the dictionary without its index page table (co_od.pages NULL, what
boards/cortex-m4 links for the bench dictionary). Everything else is the plain output."""

import re

from eds2c_testlib import generate_plain_and
from eds2c_testlib import sym as od_sym


def test_no_pages_leaves_out_the_table_only(tmp_path):
    plain, no_pages = generate_plain_and("bench", tmp_path, "no_pages", "--no-pages")
    sym = od_sym("bench")
    text, plain_text = no_pages.read_text(), plain.read_text()
    assert f"{sym}_pages" in plain_text
    assert f"{sym}_pages" not in text
    assert re.search(r"^    NULL /\* pages: .*\*/$", text, re.M)
    # the rest is the same, line for line, up to the page table (the header's name aside)
    cut = plain_text.index("/* The first entry of each index page")
    assert text.replace("no_pages.h", "plain.h").startswith(plain_text[:cut])
