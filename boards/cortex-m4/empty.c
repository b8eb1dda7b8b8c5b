/* The baseline every footprint is measured against: crt0, newlib-nano's start-up and an empty
 * loop (996 B text, 108 B data, 172 B bss with this toolchain). */
int main(void);

int main(void)
{
    for (;;) {
    }
}
