//! The hardware layer (AVR only): pins, USART, timers, EEPROM, watchdog.
