"""Cheaper kernel compiles: two costs of Taichi's Python front end that Lantern's large kernels pay.

A render kernel inlines hundreds of `ti.func`s (every BSDF lobe, light, shape and medium of the
scene's features), ~70,000 AST nodes. Profiling a cold compile of the studio scene's `mis` kernel
(cProfile, Taichi 1.7.4) showed two front-end costs that have nothing to do with the program:

- For every AST node it visits, the transformer formats the node's source excerpt with a caret
  line, through `textwrap`, in case an error must be reported there
  (`ASTTransformerContext.get_pos_info`): ~35% of the compile's CPU time.
- Every call of a `ti.func` inside a kernel reads the function's source again (`inspect` finds
  the block by tokenising the file: ~1,800 times per kernel), and re-wraps each of its lines
  through `textwrap.fill` (~17,000 calls in the textured scene's first render from the cache,
  ~8 % of its profiled time).

`install()` replaces the first by a plain excerpt (file, line, function, the source line and a
caret under single-line nodes: the same facts, still in every compile error) and caches the
second per code object (a function's source does not change while the process runs) and the
re-wrapped lines per line (a pure function of the line). Measured
on the studio scene's mis kernel (CPU seconds of a cold first render, 4 runs each, interleaved):
9.2-11.6 s before, 6.4-7.9 s after (scripts/frontend_cost.py repeats it). Images are unchanged:
the IR Taichi builds is the same, only the error-message strings differ.

Only Taichi versions whose internals match are patched (the pinned 1.7.x); others keep their own.
"""
from __future__ import annotations

_INSTALLED = "_lantern_frontend_installed"


def _plain_position(ctx, node) -> str:
    """Where `node` is, for an error message: file, line, function, the line and a caret."""
    line = ctx.src[node.lineno - 1]
    text = f'File "{ctx.file}", line {node.lineno + ctx.lineno_offset}, in {ctx.func.func.__name__}:\n{line}\n'
    if getattr(node, "end_lineno", None) == node.lineno:
        start = ctx.indent + node.col_offset
        text += " " * start + "^" * max(1, ctx.indent + node.end_col_offset - start) + "\n"
    return text


def _cached_per_code(lookup):
    """`lookup(function)` remembered per code object: the closures a program makes of one
    function share its source."""
    results = {}

    def cached(obj):
        key = getattr(obj, "__code__", obj)
        if key not in results:
            results[key] = lookup(obj)
        return results[key]

    return cached


class _LineFillCache:
    """The `textwrap` module as the front end sees it, with `fill` remembered per (line, options)."""

    def __init__(self, module):
        self._module = module
        self._filled = {}

    def fill(self, text, **options):
        key = (text, tuple(sorted(options.items())))
        if key not in self._filled:
            self._filled[key] = self._module.fill(text, **options)
        return self._filled[key]

    def __getattr__(self, name):
        return getattr(self._module, name)


def install() -> bool:
    """Patch the front end once per process; False where this Taichi's internals differ."""
    try:
        import taichi
        from taichi.lang import kernel_impl
        from taichi.lang.ast import ast_transformer_utils
    except ImportError:
        return False
    if tuple(taichi.__version__[:2]) != (1, 7):
        return False
    context = getattr(ast_transformer_utils, "ASTTransformerContext", None)
    if context is None or not hasattr(context, "get_pos_info"):
        return False
    if getattr(kernel_impl, _INSTALLED, False):
        return True
    if not (callable(getattr(kernel_impl, "getsourcelines", None))
            and callable(getattr(kernel_impl, "getsourcefile", None))):
        return False
    context.get_pos_info = _plain_position
    kernel_impl.getsourcelines = _cached_per_code(kernel_impl.getsourcelines)
    kernel_impl.getsourcefile = _cached_per_code(kernel_impl.getsourcefile)
    if getattr(kernel_impl, "textwrap", None) is not None and callable(getattr(kernel_impl.textwrap, "fill", None)):
        kernel_impl.textwrap = _LineFillCache(kernel_impl.textwrap)
    setattr(kernel_impl, _INSTALLED, True)
    return True


__all__ = ["install"]
