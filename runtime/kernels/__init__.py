"""Generated kernels at run time: naming, lock, cache and build of C modules (cffi JIT), loading of
NumPy and C kernel families, the C calling convention (abi), the checked call boundary and the
typed view of element.json.

May import: runtime.catalog, runtime.progress.  Never imports SymPy.
"""
