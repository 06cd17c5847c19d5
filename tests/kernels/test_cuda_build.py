"""The CUDA code path compiles, even on a machine without a GPU (NVRTC, sm_90 = H100)."""

from __future__ import annotations

import pytest
import warp as wp

KERNEL_MODULES = ("bodyfit.kernels.skinning", "bodyfit.kernels.raster",
                  "bodyfit.kernels.boundary", "bodyfit.kernels.alignment",
                  "bodyfit.kernels.cost")


@pytest.mark.skipif(90 not in wp.get_cuda_supported_archs(),
                    reason="this Warp build cannot compile CUDA code for sm_90")
@pytest.mark.parametrize("module", KERNEL_MODULES)
def test_kernels_compile_for_an_h100(module, tmp_path):
    __import__(module)
    artefacts = wp.compile_aot_module(module, arch=90, module_dir=tmp_path, use_ptx=True)
    assert artefacts and all(path.stat().st_size > 0 for path in artefacts)
