/* The library's identity: the hash of the sources it was built from (kernels/build.py). */
#ifndef PC_SOURCES_HASH
#error "PC_SOURCES_HASH must be defined by the build (kernels/build.py)"
#endif

const char *pc_sources_hash(void);

const char *pc_sources_hash(void)
{
    return PC_SOURCES_HASH;
}
