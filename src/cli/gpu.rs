//! `hmdist gpu list`: the adapters the GPU backends can open, and the one they take here.

use clap::Subcommand;

use hmdist::error::Result;

#[derive(Subcommand)]
pub enum GpuCommand {
    /// The Vulkan, Metal and DX12 adapters, numbered as `--gpu N` and HMDIST_GPU count them,
    /// and the one the GPU backends take here (after --gpu, HMDIST_GPU, CUDA_VISIBLE_DEVICES
    /// and SLURM_LOCALID).
    List,
}

#[cfg(feature = "gpu")]
pub fn run(command: GpuCommand) -> Result<()> {
    match command {
        GpuCommand::List => {
            let (adapters, taken) = hmdist::gpu::adapters()?;
            if adapters.is_empty() {
                println!("no Vulkan, Metal or DX12 adapter (Debian: apt install mesa-vulkan-drivers libvulkan1 for a software one, or the GPU vendor's driver)");
            }
            for a in &adapters {
                let mark = if taken.as_ref() == Some(a) { "*" } else { " " };
                let pci = if a.pci_bus.is_empty() {
                    "-"
                } else {
                    a.pci_bus.as_str()
                };
                println!(
                    "{mark} {:>2}  {:<40} {:<10} {:<7} pci {:<13} {}",
                    a.index, a.name, a.kind, a.backend, pci, a.driver
                );
            }
            match taken {
                Some(a) if a.software() => println!(
                    "* taken by --backend gpu-software; --backend gpu refuses it (a software implementation)"
                ),
                Some(_) => println!("* taken by --backend gpu (and auto)"),
                None if !adapters.is_empty() => println!("no adapter would be taken"),
                None => {}
            }
            Ok(())
        }
    }
}

#[cfg(not(feature = "gpu"))]
pub fn run(command: GpuCommand) -> Result<()> {
    let GpuCommand::List = command;
    println!("this hmdist was built without the gpu feature");
    Ok(())
}
