/* Minimal Cortex-M4 startup for QEMU netduinoplus2: vector table, reset handler (.data copy,
 * .bss zeroing, FPU on), fault handler, and ARM semihosting (output and exit). */
#include <stdint.h>

extern uint32_t _estack, _sidata, _sdata, _edata, _sbss, _ebss;
int main(void);
void semihost_exit(int ok);

void Reset_Handler(void)
{
    uint32_t *src = &_sidata, *dst = &_sdata;
    while (dst < &_edata)
        *dst++ = *src++;
    for (dst = &_sbss; dst < &_ebss; dst++)
        *dst = 0;
    /* CPACR: full access to CP10/CP11 (the FPU), needed for -mfloat-abi=hard code. */
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;
    __asm__ volatile("dsb\n isb" ::: "memory");
    semihost_exit(main() == 0);
}

static int semihost(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void semihost_write0(const char *s) { semihost(0x04, s); } /* SYS_WRITE0 */

void semihost_exit(int ok)
{
    /* SYS_EXIT (angel_SWIreason_ReportException): ADP_Stopped_ApplicationExit gives QEMU
     * exit status 0, ADP_Stopped_RunTimeErrorUnknown gives 1. */
    semihost(0x18, (const void *)(ok ? 0x20026u : 0x20023u));
    for (;;) {
    }
}

void Fault_Handler(void)
{
    semihost_write0("fault\n");
    semihost_exit(0);
}

__attribute__((section(".vectors"), used))
static const void *const vectors[16] = {
    &_estack,       /* initial SP */
    Reset_Handler,  /* reset */
    Fault_Handler,  /* NMI */
    Fault_Handler,  /* HardFault */
    Fault_Handler,  /* MemManage */
    Fault_Handler,  /* BusFault */
    Fault_Handler,  /* UsageFault */
    0, 0, 0, 0,
    Fault_Handler,  /* SVCall */
    Fault_Handler,  /* DebugMon */
    0,
    Fault_Handler,  /* PendSV */
    Fault_Handler,  /* SysTick (its interrupt stays disabled) */
};
