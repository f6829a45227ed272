"""The browser side of tuckercodec: a second decoder of the format in JavaScript, and a page that
plays a .tkc file.

``web/tkc/`` is the JavaScript decoder, ES modules written from ``spec/FORMAT.md`` alone (not
translated from the Python), checked against ``spec/vectors/`` by the tests; it runs in node
and in browsers with no build step. ``web/vendor/`` holds the npm packages it and the page use
(fzstd for Zstandard, three.js for drawing), each with its licence. ``web/viewer/`` is the page
that ``tuckercodec view`` serves and ``--export-html`` writes.
"""
