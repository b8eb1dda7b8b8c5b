/* CiA 301 SDO abort codes. Every OD access returns one of these; 0 means success. */
#ifndef CANOPEN_ABORT_H
#define CANOPEN_ABORT_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef uint32_t co_abort;

#define CO_ABORT_NONE                 0x00000000u
#define CO_ABORT_TOGGLE               0x05030000u /* toggle bit not alternated */
#define CO_ABORT_TIMEOUT              0x05040000u /* SDO protocol timed out */
#define CO_ABORT_COMMAND              0x05040001u /* client/server command specifier not valid */
#define CO_ABORT_BLOCK_SIZE           0x05040002u /* invalid block size */
#define CO_ABORT_SEQUENCE             0x05040003u /* invalid sequence number */
#define CO_ABORT_CRC                  0x05040004u /* CRC error */
#define CO_ABORT_OUT_OF_MEMORY        0x05040005u
#define CO_ABORT_UNSUPPORTED_ACCESS   0x06010000u
#define CO_ABORT_WRITE_ONLY           0x06010001u /* attempt to read a write-only object */
#define CO_ABORT_READ_ONLY            0x06010002u /* attempt to write a read-only object */
#define CO_ABORT_NO_OBJECT            0x06020000u
#define CO_ABORT_NOT_MAPPABLE         0x06040041u
#define CO_ABORT_PDO_LENGTH           0x06040042u /* number and length of mapped objects exceed PDO */
#define CO_ABORT_PARAM_INCOMPATIBLE   0x06040043u
#define CO_ABORT_DEVICE_INCOMPATIBLE  0x06040047u
#define CO_ABORT_HARDWARE             0x06060000u
#define CO_ABORT_TYPE_LENGTH          0x06070010u /* length of service parameter does not match */
#define CO_ABORT_TYPE_TOO_LONG        0x06070012u
#define CO_ABORT_TYPE_TOO_SHORT       0x06070013u
#define CO_ABORT_NO_SUBINDEX          0x06090011u
#define CO_ABORT_VALUE_RANGE          0x06090030u
#define CO_ABORT_VALUE_TOO_HIGH       0x06090031u
#define CO_ABORT_VALUE_TOO_LOW        0x06090032u
#define CO_ABORT_MAX_BELOW_MIN        0x06090036u
#define CO_ABORT_GENERAL              0x08000000u
#define CO_ABORT_STORE                0x08000020u /* data cannot be transferred or stored */
#define CO_ABORT_LOCAL_CONTROL        0x08000021u
#define CO_ABORT_DEVICE_STATE         0x08000022u
#define CO_ABORT_NO_DICTIONARY        0x08000023u
#define CO_ABORT_NO_DATA              0x08000024u

#ifdef __cplusplus
}
#endif

#endif
