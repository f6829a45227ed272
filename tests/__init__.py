"""The test suite; its shared helpers are the package :mod:`tests.support`."""
