/* Compile-time sizes of the core. Every buffer the core uses lives in the caller's co_node, so these
 * numbers decide the RAM a node takes. Override any of them with -D on the compiler command line. */
#ifndef CANOPEN_CONFIG_H
#define CANOPEN_CONFIG_H

/* Frames the core holds while the port's own queue is full. Must be a power of two. */
#ifndef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 16u
#endif

/* SDO server buffer: the largest non-DOMAIN object a segmented or block download can write (a
 * download is committed only once complete, so an aborted transfer changes nothing), and the
 * block size offered in block transfers (buffer / 7 segments, at most 127). */
#ifndef CO_SDO_BUF_SIZE
#define CO_SDO_BUF_SIZE 889u
#endif

/* Default SDO server timeout between two frames of one transfer, in microseconds. */
#ifndef CO_SDO_TIMEOUT_US
#define CO_SDO_TIMEOUT_US 1000000u
#endif

/* RPDOs and TPDOs one node handles (the dictionary's PDOs in number order; more are ignored).
 * Each costs about 110 bytes (RPDO) / 90 bytes (TPDO) of RAM on a 32-bit target. */
#ifndef CO_MAX_RPDO
#define CO_MAX_RPDO 8u
#endif
#ifndef CO_MAX_TPDO
#define CO_MAX_TPDO 8u
#endif

/* Object hooks (computed or side-effecting objects) one node can register. */
#ifndef CO_MAX_HOOKS
#define CO_MAX_HOOKS 24u
#endif

#endif
