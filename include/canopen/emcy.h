/* EMCY producer (CiA 301 §7.2.7), error register 0x1001 and pre-defined error field 0x1003. */
#ifndef CANOPEN_EMCY_H
#define CANOPEN_EMCY_H

#include <stdbool.h>
#include <stdint.h>

struct co_node;

#ifndef CO_EMCY_MAX_ACTIVE
#define CO_EMCY_MAX_ACTIVE 8u /* errors that can be active at once */
#endif
#ifndef CO_EMCY_QUEUE_LEN
#define CO_EMCY_QUEUE_LEN 4u  /* EMCY frames held back by the inhibit time (0x1015) */
#endif

/* Error register bits (0x1001). */
#define CO_ERR_REG_GENERIC       0x01u
#define CO_ERR_REG_CURRENT       0x02u
#define CO_ERR_REG_VOLTAGE       0x04u
#define CO_ERR_REG_TEMPERATURE   0x08u
#define CO_ERR_REG_COMMUNICATION 0x10u
#define CO_ERR_REG_PROFILE       0x20u
#define CO_ERR_REG_MANUFACTURER  0x80u

typedef struct co_emcy_active {
    uint16_t code;
    uint8_t register_bits;
} co_emcy_active;

typedef struct co_emcy {
    co_emcy_active active[CO_EMCY_MAX_ACTIVE];
    uint8_t active_count;
    uint32_t inhibit_us;       /* 0x1015, 100 µs units converted */
    uint64_t next_allowed;     /* earliest time the next EMCY may be sent */
    uint8_t queued[CO_EMCY_QUEUE_LEN][8];
    uint8_t queued_count;
    uint32_t lost;             /* EMCY frames dropped because the queue was full */
} co_emcy;

/* Raises an error: records code in 0x1003 (newest at sub 1, older ones shift down, depth as the
 * OD defines), sets register_bits (and the generic bit) in 0x1001, and sends an EMCY with code,
 * 0x1001 and the 5 manufacturer bytes (NULL: zeros), after the inhibit time if one is running.
 * Raising a code that is already active only sends again. Returns false if the active list is
 * full (the EMCY is still sent). */
bool co_emcy_raise(struct co_node *node, uint16_t code, uint8_t register_bits,
                   const uint8_t manufacturer[5]);

/* Clears an active error: recomputes 0x1001 from the errors still active; when none is left
 * sends the error-reset EMCY (code 0x0000). Unknown codes are ignored. */
void co_emcy_clear(struct co_node *node, uint16_t code);

/* Clears every active error (as a fault reset does), sending one error-reset EMCY. */
void co_emcy_clear_all(struct co_node *node);

/* True while code is active. */
bool co_emcy_is_active(const struct co_node *node, uint16_t code);

#endif
