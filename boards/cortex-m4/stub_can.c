/* The stub port of stub_can.h: register layouts loosely modelled on an STM32 bxCAN, at the
 * addresses such a part uses, so the code is what a real driver's would be. */
#include "stub_can.h"

#include <string.h>

typedef struct stub_mailbox {
    volatile uint32_t id;   /* bit 0: RTR, bits 21-31: standard identifier */
    volatile uint32_t dlc;
    volatile uint32_t data_low;
    volatile uint32_t data_high;
} stub_mailbox;

typedef struct stub_can_regs {
    volatile uint32_t tx_status; /* bit 0: mailbox empty */
    volatile uint32_t rx_fifo;   /* bits 0-1: frames pending; bit 5: release */
    stub_mailbox tx;
    stub_mailbox rx;
} stub_can_regs;

#define STUB_CAN ((stub_can_regs *)0x40006400u)
#define STUB_TIMER ((volatile uint32_t *)0x40000024u)   /* free-running 1 MHz counter */
#define STUB_GPIO ((volatile uint32_t *)0x40020010u)
#define STUB_FLASH_PAGE ((const uint8_t *)0x08060000u)
#define STUB_FLASH_REGS ((volatile uint32_t *)0x40023C00u)

bool stub_can_send(void *ctx, const co_frame *frame)
{
    (void)ctx;
    stub_can_regs *can = STUB_CAN;
    if ((can->tx_status & 1u) == 0u) {
        return false;
    }
    uint32_t low = 0, high = 0;
    memcpy(&low, &frame->data[0], 4);
    memcpy(&high, &frame->data[4], 4);
    can->tx.data_low = low;
    can->tx.data_high = high;
    can->tx.dlc = frame->dlc;
    can->tx.id = ((uint32_t)frame->id << 21) | ((frame->flags & CO_FRAME_RTR) != 0u ? 2u : 0u) | 1u;
    return true;
}

bool stub_can_receive(co_frame *frame)
{
    stub_can_regs *can = STUB_CAN;
    if ((can->rx_fifo & 3u) == 0u) {
        return false;
    }
    uint32_t id = can->rx.id;
    uint32_t low = can->rx.data_low, high = can->rx.data_high;
    frame->id = (uint16_t)(id >> 21);
    frame->flags = (id & 2u) != 0u ? CO_FRAME_RTR : 0u;
    frame->dlc = (uint8_t)(can->rx.dlc & 0x0Fu);
    memcpy(&frame->data[0], &low, 4);
    memcpy(&frame->data[4], &high, 4);
    can->rx_fifo = 0x20u;
    return true;
}

/* The only state of the port: the high half of the clock (a real port keeps it too). */
static uint32_t clock_high;
static uint32_t clock_last;

uint64_t stub_clock_us(void)
{
    uint32_t low = *STUB_TIMER;
    if (low < clock_last) {
        clock_high++;
    }
    clock_last = low;
    return ((uint64_t)clock_high << 32) | low;
}

uint32_t stub_input(void)
{
    return *STUB_GPIO;
}

static bool flash_load(void *ctx, uint32_t layout_hash, uint32_t offset, uint8_t *buf, uint32_t len)
{
    (void)ctx;
    const uint8_t *page = STUB_FLASH_PAGE;
    uint32_t stored_hash, stored_len;
    memcpy(&stored_hash, page, 4);
    memcpy(&stored_len, page + 4, 4);
    if (stored_hash != layout_hash || offset > stored_len || len > stored_len - offset) {
        return false;
    }
    memcpy(buf, page + 8 + offset, len);
    return true;
}

static void flash_program(uint32_t address, const uint8_t *data, uint32_t len)
{
    volatile uint32_t *regs = STUB_FLASH_REGS;
    for (uint32_t i = 0; i < len; i += 4u) {
        uint32_t word = 0;
        memcpy(&word, data + i, len - i < 4u ? len - i : 4u);
        regs[1] = address + i;
        regs[2] = word;
        while ((regs[3] & 1u) != 0u) {
        }
    }
}

static bool flash_erase(void *ctx)
{
    (void)ctx;
    volatile uint32_t *regs = STUB_FLASH_REGS;
    regs[0] = 0x08060000u;
    while ((regs[3] & 1u) != 0u) {
    }
    return (regs[3] & 2u) == 0u;
}

static bool flash_save(void *ctx, uint32_t layout_hash, const uint8_t *image, uint32_t len)
{
    if (!flash_erase(ctx)) {
        return false;
    }
    uint8_t header[8];
    memcpy(header, &layout_hash, 4);
    memcpy(header + 4, &len, 4);
    flash_program(0x08060000u, header, 8);
    flash_program(0x08060008u, image, len);
    return (STUB_FLASH_REGS[3] & 2u) == 0u;
}

const co_storage stub_flash_storage = {flash_load, flash_save, flash_erase, NULL};
