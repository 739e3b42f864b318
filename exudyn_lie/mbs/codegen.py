"""Compiled functions generated from a registry (the force elements' ``compute_forces``, the
step observers' ``after_accepted_step``): one call per registration, written out as source so
that numba inlines each call, as if the function had been written by hand."""


def generate(name, header, lines, footer, env, doc, module):
    """The function ``name`` of the source ``header`` + indented ``lines`` + ``footer``, with the
    globals ``env``, compiled under the file of ``module`` (a module object) so that numba caches
    it with that module (the cache key, exudyn_lie._numba_cache, hashes every package file)."""
    src = "\n".join([header] + ["    " + x for x in lines] + ["    " + x for x in footer]) + "\n"
    exec(compile(src, module.__file__, "exec"), env)
    fn = env[name]
    fn.__module__ = module.__name__
    fn.__doc__ = doc
    return fn
