/* A user's switch header (CO_CONFIG_USER_HEADER) that the library under test was not built with. */
#define CO_CONFIG_TIME32 1
