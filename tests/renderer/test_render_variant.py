"""Variant choice: override argument, CASSI_VARIANT, libLLVM discovery (>= 16 only)."""
from __future__ import annotations

import pytest

from cassi.common.errors import CassiInputError
from cassi.renderer import variant as V

pytestmark = pytest.mark.render


def test_override_short_and_full_names(monkeypatch):
    monkeypatch.delenv("CASSI_VARIANT", raising=False)
    assert V.choose_variant("scalar") == "scalar_rgb"
    assert V.choose_variant("scalar_rgb") == "scalar_rgb"


def test_env_variable_used_and_argument_wins(monkeypatch):
    monkeypatch.setenv("CASSI_VARIANT", "scalar")
    assert V.choose_variant() == "scalar_rgb"
    monkeypatch.setenv("CASSI_VARIANT", "no_such_variant")
    assert V.choose_variant("scalar") == "scalar_rgb"
    with pytest.raises(CassiInputError, match="unknown render variant"):
        V.choose_variant()


def test_unknown_variant_is_input_error(monkeypatch):
    monkeypatch.delenv("CASSI_VARIANT", raising=False)
    with pytest.raises(CassiInputError, match="unknown render variant 'vulkan'"):
        V.choose_variant("vulkan")


def test_find_libllvm_respects_env_and_minimum(tmp_path, monkeypatch):
    old = tmp_path / "libLLVM-14.so"
    new = tmp_path / "libLLVM-19.so"
    old.write_bytes(b"")
    new.write_bytes(b"")
    monkeypatch.setattr(V, "_LLVM_GLOBS", (str(tmp_path / "libLLVM*.so*"),))
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(new))
    assert V.find_libllvm() == V.LLVMLibrary(new, 19)
    # an LLVM older than 16 named by the variable is passed over for a usable one
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(old))
    assert V.find_libllvm() == V.LLVMLibrary(new, 19)
    new.unlink()
    assert V.find_libllvm() is None
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH")
    (tmp_path / "libLLVM.so.17.1").write_bytes(b"")
    assert V.find_libllvm().version == 17


def test_automatic_choice_is_the_fastest_usable(monkeypatch):
    import drjit as dr

    monkeypatch.delenv("CASSI_VARIANT", raising=False)
    chosen = V.choose_variant()
    if dr.has_backend(dr.JitBackend.CUDA):
        assert chosen == "cuda_ad_rgb"
    elif V.find_libllvm() is not None:
        assert chosen == "llvm_ad_rgb"
    else:
        assert chosen == "scalar_rgb"


def test_automatic_choice_without_llvm_falls_back_to_scalar(monkeypatch):
    monkeypatch.delenv("CASSI_VARIANT", raising=False)
    monkeypatch.setattr(V, "_cuda_usable", lambda: False)
    monkeypatch.setattr(V, "find_libllvm", lambda **kw: None)
    assert V.choose_variant() == "scalar_rgb"
    with pytest.raises(CassiInputError, match="not usable"):
        V.choose_variant("llvm")
