/* The microsecond clock of the blank port (port.h): a free-running 32-bit hardware counter at
 * 1 MHz, widened to 64 bits by its overflow interrupt, so that port_clock_us() never wraps (the
 * core's API times are 64-bit µs; a 32-bit count alone would wrap after 71.6 minutes). */
#include "port.h"

static volatile uint32_t clock_high; /* overflows of the counter */

/* TODO: the hardware counter (e.g. a 32-bit timer clocked at 1 MHz). The stand-in advances one
 * µs per read, so a host build of this port sees time pass. */
static uint32_t hw_counter(void)
{
    static uint32_t fake;
    return ++fake;
}

/* TODO: true while the counter's overflow flag is set and its interrupt not yet handled. */
static bool hw_overflow_pending(void)
{
    return false;
}

void port_clock_init(void)
{
    /* TODO: start the counter at 1 MHz, counting up from 0 to 2^32 - 1, with its overflow
     * interrupt enabled; a compare channel for port_sleep_until(). */
    clock_high = 0;
}

void port_timer_overflow_isr(void)
{
    /* TODO: acknowledge the overflow flag. */
    clock_high++;
}

uint64_t port_clock_us(void)
{
    /* The counter and its high half are read with the overflow interrupt masked; an overflow
     * pending but not yet counted is counted here (the counter has wrapped to a small value). */
    uint32_t key = port_lock();
    uint32_t high = clock_high;
    uint32_t low = hw_counter();
    if (hw_overflow_pending() && low < 0x80000000u) {
        high++;
    }
    port_unlock(key);
    return ((uint64_t)high << 32) | low;
}

void port_sleep_until(uint64_t deadline)
{
    /* Masked, so that an interrupt between the test and the sleep cannot be missed: a Cortex-M
     * wakes from WFI on a pending interrupt even while PRIMASK masks it, and runs its handler at
     * port_unlock(). */
    uint32_t key = port_lock();
    if (!port_can_pending() && port_clock_us() < deadline) {
        /* TODO: unless deadline is CO_TIME_NEVER, set the timer's compare channel to interrupt
         * at deadline (if it lies more than one counter period ahead, the overflow interrupt
         * wakes the loop first, which then sleeps again); then __WFI(). */
    }
    port_unlock(key);
}

/* TODO: on a Cortex-M, with CMSIS:
 *   uint32_t port_lock(void) { uint32_t k = __get_PRIMASK(); __disable_irq(); return k; }
 *   void port_unlock(uint32_t k) { __set_PRIMASK(k); }
 * (or BASEPRI to mask only the CAN and timer interrupts). Under an RTOS, a critical section
 * of the kernel. The stand-ins do nothing: this build has no interrupts. */
uint32_t port_lock(void)
{
    return 0;
}

void port_unlock(uint32_t key)
{
    (void)key;
}
