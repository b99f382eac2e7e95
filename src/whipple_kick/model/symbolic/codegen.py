"""Turning the symbolic equations into code (the build side): NumPy source; C is printed by :mod:`.slip_build`.

The generated NumPy functions accept complex arrays as well as real ones,
which is what lets :mod:`.classic` linearise by complex-step differentiation
(derivatives exact to round-off, no step-size trade-off).
"""
import sympy as sm
from sympy.printing.numpy import NumPyPrinter


def plain(expr_or_matrix, dynamic):
    """Replace dynamicsymbols ``x(t)`` by plain symbols named ``x``."""
    mapping = {d: sm.Symbol(d.func.__name__, real=True) for d in dynamic}
    if isinstance(expr_or_matrix, sm.MatrixBase):
        return expr_or_matrix.xreplace(mapping)
    return sm.sympify(expr_or_matrix).xreplace(mapping)


def plain_symbol(dynamic_symbol):
    """The plain symbol :func:`plain` substitutes for a dynamicsymbol."""
    return sm.Symbol(dynamic_symbol.func.__name__, real=True)


def numpy_function(name, arguments, outputs, doc=""):
    """Source of one NumPy function computing several outputs with shared CSE.

    Parameters
    ----------
    name : str
        Function name.
    arguments : list of (str, sequence of sympy.Symbol)
        Each argument is a 1-D array whose entries are these symbols, in order.
    outputs : list of sympy.Matrix or sympy.Expr
        Returned as a tuple, matrices as 2-D arrays (column vectors as 1-D).
    doc : str
        Docstring of the generated function.

    Returns
    -------
    str
        Python source.
    """
    printer = NumPyPrinter({"fully_qualified_modules": True, "inline": True})
    flat, shapes = [], []
    for out in outputs:
        if isinstance(out, sm.MatrixBase):
            shapes.append(out.shape)
            flat.extend(list(out))
        else:
            shapes.append(None)
            flat.append(sm.sympify(out))
    replacements, reduced = sm.cse(flat, symbols=sm.numbered_symbols("_x"), order="none")
    lines = [f"def {name}({', '.join(a for a, _ in arguments)}):", f'    """{doc}"""']
    # A zero of the first argument's dtype (complex under complex-step), so
    # constant entries of the outputs take the same dtype.
    lines.append("    _z = numpy.zeros_like(numpy.asarray(" + arguments[0][0] + ")[0])")
    for arg, syms in arguments:
        if syms:
            lines.append(f"    {', '.join(str(s) for s in syms)}, = {arg}")
    for lhs, rhs in replacements:
        lines.append(f"    {lhs} = {printer.doprint(rhs)}")
    results, k = [], 0
    for shape in shapes:
        if shape is None:
            results.append(f"({printer.doprint(reduced[k])}) + _z")
            k += 1
            continue
        rows, cols = shape
        entries = [f"({printer.doprint(e)}) + _z" for e in reduced[k:k + rows * cols]]
        k += rows * cols
        if cols == 1:
            results.append("numpy.array([" + ", ".join(entries) + "])")
        else:
            body = ", ".join("[" + ", ".join(entries[r * cols:(r + 1) * cols]) + "]" for r in range(rows))
            results.append(f"numpy.array([{body}])")
    lines.append("    return (" + ", ".join(results) + ",)")
    return "\n".join(lines) + "\n"


__all__ = ["numpy_function", "plain", "plain_symbol"]
