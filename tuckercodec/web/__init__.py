"""The browser side of tuckercodec: a second decoder of the format in JavaScript, and a page that
plays a .tkc file.

``web/tkc/`` is the JavaScript decoder, ES modules written from ``spec/FORMAT.md`` alone (not
translated from the Python), checked against ``spec/vectors/`` by the tests; it runs in node
and in browsers with no build step. ``web/vendor/`` holds the npm packages it and the page use
(fzstd for Zstandard, three.js for drawing), each with its licence. ``web/three/`` is
``TKCLoader``, the three.js loader that plays a file on a mesh, and ``web/viewer/`` the page
that ``tuckercodec view`` serves and ``--export-html`` writes, which plays the file with it.

The folder is also the root of the npm package ``tuckercodec`` (``package.json``, ``README.md``,
``LICENSE``): the decoder, the loader, fzstd, and ``web/types/``, the TypeScript declarations
tsc emits from their JSDoc (``tools/js``).
"""
