"""Instruction embeddings encoded one text at a time and remembered on disk (generator.embedding): the same
vectors as encoding each text alone, read back without the model, damaged or unwritable caches survived."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from generator import embedding

TEXTS = ["Put the apple into the bowl.", "Open the left-hinged cabinet's door by its handle.",
         "Lift the golf ball off the table."]


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GENDEX_CACHE", str(tmp_path))
    monkeypatch.setattr(embedding, "_MEMO", {})
    return tmp_path


def _no_model():
    raise AssertionError("the model was loaded although every vector is cached")


def test_each_text_is_encoded_alone_and_read_back_from_disk_without_the_model(fresh_cache, monkeypatch):
    vecs, source = embedding.embed_each(TEXTS)
    assert vecs.shape == (3, embedding.DIMENSIONS) and vecs.dtype == np.float32 and "all-MiniLM-L6-v2" in source
    for text, vec in zip(TEXTS, vecs, strict=True):
        np.testing.assert_array_equal(vec, embedding.embed([text])[0][0])  # as if encoded on its own
    np.testing.assert_allclose(np.linalg.norm(vecs, axis=1), 1.0, atol=1e-5)
    # a vector does not depend on the texts encoded with it or before it
    np.testing.assert_array_equal(embedding.embed_each([TEXTS[2], "Close the drawer."])[0][0], vecs[2])
    files = sorted(embedding.cache_dir().rglob("*.npy"))
    assert len(files) == 4 and embedding.cache_dir().is_relative_to(fresh_cache)

    monkeypatch.setattr(embedding, "_MEMO", {})  # another process: only the disk remains
    monkeypatch.setattr(embedding, "_minilm", _no_model)
    again, _ = embedding.embed_each([TEXTS[1], TEXTS[0], TEXTS[1]])
    np.testing.assert_array_equal(again, vecs[[1, 0, 1]])
    assert embedding.embed_each([])[0].shape == (0, embedding.DIMENSIONS)


def test_a_damaged_entry_is_encoded_again_and_repaired(fresh_cache, monkeypatch, caplog):
    want = embedding.embed_each(TEXTS[:1])[0][0]
    (path,) = embedding.cache_dir().rglob("*.npy")
    for damage in (b"not a numpy file", None):
        if damage is None:  # a readable array of the wrong shape
            np.save(path, np.zeros(7, np.float32))
        else:
            path.write_bytes(damage)
        monkeypatch.setattr(embedding, "_MEMO", {})
        with caplog.at_level(logging.INFO, logger=embedding.__name__):
            got = embedding.embed_each(TEXTS[:1])[0][0]
        np.testing.assert_array_equal(got, want)
        assert str(path) in caplog.text
        np.testing.assert_array_equal(np.load(path), want)  # rewritten
        caplog.clear()


def test_an_unwritable_cache_keeps_vectors_in_the_process(tmp_path, monkeypatch, caplog):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder would be")
    monkeypatch.setenv("GENDEX_CACHE", str(blocker))
    monkeypatch.setattr(embedding, "_MEMO", {})
    with caplog.at_level(logging.INFO, logger=embedding.__name__):
        vecs, _ = embedding.embed_each(TEXTS[:2])
    assert "not written" in caplog.text and blocker.read_text().startswith("a file")
    monkeypatch.setattr(embedding, "_minilm", _no_model)
    np.testing.assert_array_equal(embedding.embed_each(TEXTS[:2])[0], vecs)  # remembered in this process


def test_without_the_stats_extra_the_error_names_what_is_missing(monkeypatch):
    import importlib.metadata

    real = importlib.metadata.version

    def version(dist):
        if dist == "sentence-transformers":
            raise importlib.metadata.PackageNotFoundError(dist)
        return real(dist)

    monkeypatch.setattr(importlib.metadata, "version", version)
    embedding._code_key.cache_clear()
    try:
        with pytest.raises(ImportError, match="sentence-transformers is not installed") as info:
            embedding.embed_each(TEXTS[:1])
        assert info.value.name == "sentence-transformers"
    finally:
        embedding._code_key.cache_clear()
