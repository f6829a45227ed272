"""What the tests share besides fixtures (those stay in tests/conftest.py), imported as
``from tests.support.NAME import ...``:

- :mod:`~tests.support.sequences`: synthetic animations and the real sequences of ../shared/data;
- :mod:`~tests.support.properties`: the hypothesis settings and strategies;
- :mod:`~tests.support.compressed`: conformance vectors taken apart, edited and decoded;
- :mod:`~tests.support.inputs`: OBJ and .npz inputs, and what a reader's answer must be;
- :mod:`~tests.support.isolation_hooks`, :mod:`~tests.support.streaming_hooks`: readers and
  frame sources that crash, hang or fail, for the isolated child's tests;
- :mod:`~tests.support.js_decoder`, :mod:`~tests.support.js_interop`: the JavaScript decoder,
  the glTF validator and three.js run in node;
- :mod:`~tests.support.browser`, :mod:`~tests.support.png`: headless Chromium driven over the
  DevTools protocol, and its screenshots read.
"""
