"""numba's compile in less time: two of its costs that make nothing, removed where this
package's processes compile (a command, its compile children, a sweep's workers, the test
suite; the Python API leaves numba as it is).  numba types, lowers and optimises the same
IR either way: the LLVM IR of the loop and of a broached hole's law is the same text with
and without them (tests/test_cold_start.py), so the same machine code and cached kernels.

1. **The inliner's copies** (``inline="always"``).  numba deep-copies the IR of a helper it
   inlines block by block, each block with a copy memo of its own, so each block's copy
   copies the helper's whole scope, every variable of it: blocks × variables, twice per
   call site (numba issue #8989, numba-cuda #688).  Here the blocks of one copy share one
   memo, as one deep copy of the whole IR would: the scope is copied once, and the blocks
   of the copy share it as the blocks of the helper do.  A copy starts with
   ``FunctionIR.copy`` (the inliner's ``copy_ir``), which starts a new memo.
2. **The flags' comparisons.**  numba's typing caches each overload's implementation under
   a key that holds the compile flags (a ``TargetConfig``).  Their hash is that of the
   option names, alike for every flags object, and their equality built a dict of every
   option, read through a property, on both sides: 170,000 dicts in a broached tube's
   first run.  Here the hash is computed from the names directly, and two flags compare
   the options either has set (where neither has, both hold the default).

The first run of a broached tube compiled in 9.7 CPU s instead of 10.9 on one core, and
on two cores the three tubes' first runs took 0.3-0.4 s less (docs/design.md, "The whole
command").  Each is applied only where numba's code is as measured (numba 0.68: its
source and its answers checked first); elsewhere numba runs as it is.
"""
from __future__ import annotations

import copy
import inspect
import types

_APPLIED = False


def apply() -> None:
    """Remove the two costs above from this process's numba (once; what does not match
    numba's code as measured is left as it is)."""
    global _APPLIED
    if _APPLIED:
        return
    _APPLIED = True
    _one_memo_per_copy()
    _quick_flags()


def _one_memo_per_copy() -> None:
    from numba.core import inline_closurecall, ir
    source = inspect.getsource(inline_closurecall.InlineWorker.inline_ir)
    if inline_closurecall.copy is not copy or "kernel_copy = the_ir.copy()" not in source \
            or "copy.deepcopy(the_ir.blocks[block_label])" not in source:
        return
    state = types.SimpleNamespace(memo={})
    function_copy = ir.FunctionIR.copy

    def copy_starting(self):
        state.memo = {}         # a new copy of an IR: its blocks share this memo
        return function_copy(self)

    def deepcopy(x, memo=None):
        if memo is None and isinstance(x, ir.Block):
            return copy.deepcopy(x, state.memo)
        return copy.deepcopy(x, memo)

    shim = types.ModuleType("copy")     # the copy module, but for deepcopy
    shim.__dict__.update(vars(copy))
    shim.deepcopy = deepcopy
    ir.FunctionIR.copy = copy_starting
    inline_closurecall.copy = shim


def _quick_flags() -> None:
    from numba.core import compiler, targetconfig
    config = targetconfig.TargetConfig
    values, equal, hashed = config.values, config.__eq__, config.__hash__

    def quick_values(self):
        given = self._values
        return {k: given.get(k, option._default) for k, option in self.options.items()}

    def quick_equal(self, other):
        if type(other) is not type(self):
            return equal(self, other)
        # alike where neither is set (both the default); compared where either is
        a, b, options = self._values, other._values, self.options
        for k in a.keys() | b.keys():
            default = options[k]._default
            x, y = a.get(k, default), b.get(k, default)
            if not (x is y or x == y):
                return False
        return True

    def quick_hash(self):
        return hash(tuple(sorted(self.options)))   # sorted(values()): the names alone

    some = compiler.Flags()
    some.nrt, some.no_cpython_wrapper = True, True
    for f, g in ((some, compiler.Flags()), (compiler.Flags(), compiler.Flags()),
                 (some, some.copy())):
        if quick_values(f) != values(f) or quick_equal(f, g) != equal(f, g) \
                or quick_hash(f) != hashed(f):
            return      # not numba's code as measured: numba as it is
    config.values, config.__eq__, config.__hash__ = quick_values, quick_equal, quick_hash
