/* A user's switch header (CO_CONFIG_USER_HEADER) with the other CO_CONFIG_TIME32 than the library
 * under test was built with (the default, or the size preset's -D). */
#if defined(CO_CONFIG_TIME32) && CO_CONFIG_TIME32
#undef CO_CONFIG_TIME32
#define CO_CONFIG_TIME32 0
#else
#undef CO_CONFIG_TIME32
#define CO_CONFIG_TIME32 1
#endif
