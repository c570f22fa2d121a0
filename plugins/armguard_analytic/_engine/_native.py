"""Calls from one compiled kernel to another through its address instead of a link.

When a numba function calls another, numba links the callee's whole compiled tree into the
caller's module and LLVM optimises and generates machine code for all of it again: each thin entry
point over the fused kernel (``detect_entry``, ``pair_rows`` and their GIL-holding twins) cost 4.5-6 s
of a cold compile (``python -m bench compile``), ~20 s of the first run's compile work, for a few
lines of its own.  An entry point that calls the fused kernel through :func:`native_caller` instead
compiles its own lines only: the callee is called at the address of its native function, which
:func:`native_address` looks up (compiling or loading it) in the calling process and the caller
passes in as an ``int64`` argument.  The call is numba's own calling convention (the one a linked
call uses), so an exception raised in the callee propagates to the caller as before.

An address is valid in the process that looked it up only: callers get it from
:func:`native_address` in that process and pass it at each call, never store it in a buffer that
could be pickled to another process.  The callee's argument types are fixed where the caller is
defined (:func:`native_caller`), and the caller is typed against them: a call with other types is
a compile error, never a call with the wrong layout.
"""

from __future__ import annotations

import threading

from numba import types
from numba.core import cgutils
from numba.core.errors import TypingError
from numba.extending import intrinsic

__all__ = ["native_address", "native_caller"]

_lock = threading.Lock()
_addresses: dict = {}


def native_caller(restype, argtypes: tuple):
    """An intrinsic ``call(fn, args)``: call the compiled function at address ``fn`` (``int64``, from
    :func:`native_address` with the same ``restype`` and ``argtypes``) with the tuple ``args``,
    whose types must be ``argtypes`` exactly, returning its ``restype`` value."""
    argtypes = tuple(argtypes)

    @intrinsic
    def call(typingctx, fn, args):  # pragma: no cover - compiled
        if not isinstance(fn, types.Integer):
            raise TypingError(f"native call: the address must be an integer, got {fn}")
        got = tuple(getattr(args, "types", ()))
        if got != argtypes:
            raise TypingError(f"native call: arguments {got} do not match the callee's {argtypes}")
        sig = restype(fn, args)

        def codegen(context, builder, signature, llargs):
            values = [builder.extract_value(llargs[1], i) for i in range(len(argtypes))]
            fnty = context.call_conv.get_function_type(restype, list(argtypes))
            ptr = builder.inttoptr(llargs[0], fnty.as_pointer())
            status, res = context.call_conv.call_function(builder, ptr, restype, list(argtypes), values)
            with cgutils.if_unlikely(builder, status.is_error):
                context.call_conv.return_status_propagate(builder, status)
            return res

        return sig, codegen

    return call


def native_address(dispatcher, restype, argtypes: tuple) -> int:
    """The address, in this process, of ``dispatcher``'s native function for ``argtypes`` (compiled,
    or loaded from numba's cache, on the first call; one look-up per process, whichever thread asks).
    Raises ``TypeError`` when that overload does not return ``restype``."""
    key = (dispatcher, restype, tuple(argtypes))
    try:
        return _addresses[key]
    except KeyError:
        pass
    with _lock:
        if key not in _addresses:
            dispatcher.compile(tuple(argtypes))
            cres = dispatcher.overloads[tuple(argtypes)]
            if cres.signature.return_type != restype:
                raise TypeError(f"{dispatcher.py_func.__qualname__} returns {cres.signature.return_type}, "
                                f"its native callers expect {restype}")
            _addresses[key] = int(cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name))
    return _addresses[key]
