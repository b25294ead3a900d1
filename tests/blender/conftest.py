"""Fixtures for the Blender tests: scenes are built in-process by scenes/build_scenes.py."""
import os
import tempfile

import pytest

import build_scenes


@pytest.fixture
def scene_factory():
    """build(name, **overrides) → a freshly built bpy Scene in an otherwise empty file."""
    def build(name, **kwargs):
        build_scenes.reset_file()
        return build_scenes.build(name, **kwargs)
    return build


@pytest.fixture(scope="session")
def outdir():
    """Where failing tests leave their images (kept for a look)."""
    d = os.environ.get("LANTERN_TEST_OUT") or tempfile.mkdtemp(prefix="lantern_blender_tests_")
    os.makedirs(d, exist_ok=True)
    return d
